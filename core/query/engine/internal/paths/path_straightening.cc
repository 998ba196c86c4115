#include "core/query/engine/internal/paths/path_straightening.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "absl/container/inlined_vector.h"
#include "core/geometry/planar_unfolding.h"
#include "core/geometry/vec2.h"
#include "core/query/engine/internal/paths/strip_funnel.h"

namespace geodex::query {
namespace {

constexpr double kZero = 1e-12;  // barycentric weights below this are on an edge
// Per-pass working arrays: most straightened paths are short (a near pair
// crosses a handful of faces), so they live on the stack until they grow.
template <typename T>
using Small = absl::InlinedVector<T, 16>;

using geometry::Cross;
using geometry::Vec2;

// The vertices a point is a convex combination of (weights > kZero).
struct Support {
  int count = 0;
  std::array<int32_t, 3> vertex;
};

class Straightener {
 public:
  explicit Straightener(const MeshView& mesh) : mesh_(mesh) {}

  // Where the funnel wraps around a vertex, the path becomes a vertex point;
  // the next pass releases it to the vertex's narrower side, which may hold
  // a shortcut the strip did not. Passes stop when nothing shortens.
  std::vector<PathPoint> Run(std::vector<PathPoint> path) {
    double length = PathLength(path);
    for (int pass = 0; pass < 256 && path.size() >= 3; ++pass) {
      std::vector<PathPoint> straight;
      if (!Straighten(path, &straight)) break;
      const double shorter = PathLength(straight);
      if (!(shorter < length * (1 - 1e-14))) break;
      path = std::move(straight);
      length = shorter;
      // Without vertex points to release, another pass builds the same strip.
      if (!WrapsRoundAVertex(path)) break;
    }
    return path;
  }

 private:
  Support SupportOf(const SurfacePoint& p) const {
    Support s;
    for (int i = 0; i < 3; ++i) {
      if (p.w[i] > kZero) {
        s.vertex[s.count++] = mesh_.Vertex(p.face, i);
      }
    }
    return s;
  }
  // The face across the edge (a, b) of face f, or -1.
  int32_t Across(int32_t f, int32_t a, int32_t b) const {
    for (int i = 0; i < 3; ++i) {
      const int32_t u = mesh_.Vertex(f, i), w = mesh_.Vertex(f, (i + 1) % 3);
      if ((u == a && w == b) || (u == b && w == a)) {
        const int32_t t = mesh_.twins[3 * f + i];
        return t < 0 ? -1 : t / 3;
      }
    }
    return -1;
  }

  // The strip unfolded (flat.portals[j] lies between faces[j] and
  // faces[j + 1]), with the run's ends' mesh vertices (-1 unless a vertex
  // point).
  struct Strip {
    UnfoldedStrip flat;
    std::span<const int32_t> faces;
    int32_t start_vertex, end_vertex;
  };

  // A face holding the point, and each face holding both it and `other`.
  Small<int32_t> FacesOf(const SurfacePoint& p, const Support& s) const {
    if (s.count == 3) return {p.face};
    if (s.count == 2) {
      const int32_t g = Across(p.face, s.vertex[0], s.vertex[1]);
      return g >= 0 ? Small<int32_t>{p.face, g} : Small<int32_t>{p.face};
    }
    Small<int32_t> out;
    mesh_.FacesAround(s.vertex[0], p.face, &out);
    return out;
  }

  // The faces around v strictly after `from` up to `to`, on the side whose
  // angle at v is smaller (the side a shortest path hugs). False if neither
  // side connects them (boundary on both).
  bool Fan(int32_t v, int32_t from, int32_t to, Small<int32_t>* fan) const {
    double best = std::numeric_limits<double>::infinity();
    Small<int32_t> between;
    for (int dir = 0; dir < 2; ++dir) {
      if (!FacesBetween(mesh_, v, from, to, dir, &between)) continue;
      double angle = 0;
      for (int32_t f : between) angle += CornerAngle(mesh_, f, v);
      if (angle < best) {
        best = angle;
        *fan = between;
        fan->push_back(to);
      }
    }
    return best < std::numeric_limits<double>::infinity();
  }

  // Shortest path through the strip of faces the path crosses, with the
  // path's vertex points released to the narrower side of their vertex.
  // False when the path is not a proper strip (then it is kept as is).
  bool Straighten(const std::vector<PathPoint>& run, std::vector<PathPoint>* out) const {
    const size_t k = run.size();
    Small<Support> support(k);
    for (size_t i = 0; i < k; ++i) support[i] = SupportOf(run[i].point);
    Small<int32_t> seg(k - 1, -1);
    if (!SegmentFaces(run, support, &seg)) return false;
    Small<int32_t> strip = {seg[0]};
    if (!BuildStrip(support, seg, &strip)) return false;
    Strip unfolded;
    if (!Unfold(run, strip, support, &unfolded)) return false;
    const UnfoldedStrip& flat = unfolded.flat;
    return Rebuild(run, unfolded, Funnel(flat.start, flat.portals, flat.end), out);
  }

  // Segment faces: segment i (run[i] -> run[i+1]) lies in face (*seg)[i].
  // False if a segment lies in no face.
  bool SegmentFaces(const std::vector<PathPoint>& run, const Small<Support>& support,
                    Small<int32_t>* seg_out) const {
    const size_t k = run.size();
    Small<int32_t>& seg = *seg_out;
    for (size_t i = 0; i + 1 < k; ++i) {
      for (int32_t f : FacesOf(run[i].point, support[i])) {
        if (FaceHolds(mesh_, f, run[i + 1].point)) {
          seg[i] = f;
          break;
        }
      }
      if (seg[i] < 0) return false;
    }
    return true;
  }

  // The strip: faces in order (*strip starts with the first segment's face),
  // each sharing an edge with the one before. False if the path does not
  // cross from face to face over shared edges or round a vertex.
  bool BuildStrip(const Small<Support>& support, const Small<int32_t>& seg,
                  Small<int32_t>* strip_out) const {
    const size_t k = support.size();
    Small<int32_t>& strip = *strip_out;
    // Entering the face just left (back across the same edge) cancels out.
    auto push = [&](int32_t face) {
      if (strip.size() >= 2 && strip[strip.size() - 2] == face) {
        strip.pop_back();
      } else {
        strip.push_back(face);
      }
    };
    for (size_t i = 1; i + 1 < k; ++i) {
      const int32_t prev = strip.back(), next = seg[i];
      if (next == prev) continue;
      if (support[i].count == 2) {
        const int32_t a = support[i].vertex[0], b = support[i].vertex[1];
        if (Across(prev, a, b) != next) return false;
        push(next);
      } else if (support[i].count == 1) {
        const int32_t v = support[i].vertex[0];
        Small<int32_t> fan;
        if (!Fan(v, prev, next, &fan)) return false;
        // Consecutive faces of a fan share an edge (UnfoldStrip checks it).
        for (int32_t f : fan) push(f);
      } else {
        return false;
      }
    }
    if (strip.size() > 1 && strip.back() != seg[k - 2]) return false;
    return true;
  }

  // Unfolds the strip (query::UnfoldStrip). False if two faces of it share
  // no edge or the end is not in its last face.
  bool Unfold(const std::vector<PathPoint>& run, const Small<int32_t>& strip,
              const Small<Support>& support, Strip* out) const {
    const size_t k = support.size();
    if (!UnfoldStrip(mesh_, strip, run[0].point, run[k - 1].point, kZero, &out->flat)) return false;
    if (!FaceHolds(mesh_, strip.back(), run[k - 1].point)) return false;
    out->faces = strip;
    out->start_vertex = support[0].count == 1 ? support[0].vertex[0] : -1;
    out->end_vertex = support[k - 1].count == 1 ? support[k - 1].vertex[0] : -1;
    return true;
  }

  // Rebuild the path: the crossings of each straight section with the
  // portals it passes, and the bends as vertex points. False on a
  // degenerate crossing.
  bool Rebuild(const std::vector<PathPoint>& run, const Strip& strip, const FunnelPath& funnel,
               std::vector<PathPoint>* out) const {
    // The path's vertices: the start, the bends, the end, each with its
    // place in the sequence of portals (the start before the first, the end
    // after the last) and its mesh vertex.
    struct Stop {
      size_t after;  // the portals strictly before it: [0, after)
      Vec2 at;
      int32_t vertex;
    };
    const size_t count = funnel.bends.size();
    auto stop = [&](size_t s) -> Stop {
      if (s == 0) return {0, strip.flat.start, strip.start_vertex};
      if (s > count) return {strip.flat.portals.size() + 1, strip.flat.end, strip.end_vertex};
      const FunnelBend& bend = funnel.bends[s - 1];
      const Portal& portal = strip.flat.portals[bend.portal];
      return {bend.portal + 1, portal.ends[bend.side], portal.vertices[bend.side]};
    };
    out->assign({run[0]});
    for (size_t s = 0; s <= count; ++s) {
      const Stop a = stop(s), b = stop(s + 1);
      const Vec2 dir = b.at - a.at;
      for (size_t j = a.after; j + 1 < b.after; ++j) {
        const Portal& portal = strip.flat.portals[j];
        const Vec2 &left = portal.ends[Portal::kLeft], &right = portal.ends[Portal::kRight];
        const int32_t left_id = portal.vertices[Portal::kLeft],
                      right_id = portal.vertices[Portal::kRight];
        if ((a.vertex >= 0 && (left_id == a.vertex || right_id == a.vertex)) ||
            (b.vertex >= 0 && (left_id == b.vertex || right_id == b.vertex))) {
          continue;  // the section passes through this portal's end
        }
        const double denom = Cross(dir, left - right);
        if (denom == 0) return false;
        const double t = std::clamp(Cross(dir, a.at - right) / denom, 0.0, 1.0);
        SurfacePoint point{strip.faces[j], {0, 0, 0}};
        for (int c = 0; c < 3; ++c) {
          const int32_t v = mesh_.Vertex(point.face, c);
          if (v == right_id) point.w[c] = 1 - t;
          if (v == left_id) point.w[c] = t;
        }
        out->push_back({point, (1 - t) * mesh_.Position(right_id) + t * mesh_.Position(left_id)});
      }
      if (s < count) {
        SurfacePoint point{strip.faces[b.after - 1], {0, 0, 0}};
        for (int c = 0; c < 3; ++c) {
          if (mesh_.Vertex(point.face, c) == b.vertex) point.w[c] = 1;
        }
        out->push_back({point, mesh_.Position(b.vertex)});
      }
    }
    out->push_back(run.back());
    return true;
  }

 private:
  const MeshView& mesh_;
};

}  // namespace

std::vector<PathPoint> StraightenPath(const MeshView& mesh, std::vector<PathPoint> path) {
  return Straightener(mesh).Run(std::move(path));
}

bool WrapsRoundAVertex(const std::vector<PathPoint>& path) {
  for (size_t i = 1; i + 1 < path.size(); ++i) {
    const std::array<double, 3>& w = path[i].point.w;
    if (w[0] == 1 || w[1] == 1 || w[2] == 1) return true;
  }
  return false;
}

}  // namespace geodex::query
