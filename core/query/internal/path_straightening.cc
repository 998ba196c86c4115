#include "core/query/internal/path_straightening.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "absl/container/inlined_vector.h"
#include "core/geometry/planar_unfolding.h"

namespace geodex::query {
namespace {

constexpr double kZero = 1e-12;  // barycentric weights below this are on an edge
// Per-pass working arrays: most straightened paths are short (a near pair
// crosses a handful of faces), so they live on the stack until they grow.
template <typename T>
using Small = absl::InlinedVector<T, 16>;

struct Vec2 {
  double x, y;
  Vec2 operator-(const Vec2& o) const { return {x - o.x, y - o.y}; }
  Vec2 operator+(const Vec2& o) const { return {x + o.x, y + o.y}; }
  Vec2 operator*(double s) const { return {x * s, y * s}; }
};
inline double Cross(const Vec2& a, const Vec2& b) { return a.x * b.y - a.y * b.x; }

// The vertices a point is a convex combination of (weights > kZero).
struct Support {
  int count = 0;
  std::array<int32_t, 3> vertex;
  std::array<double, 3> weight;
};

class Straightener {
 public:
  explicit Straightener(const MeshView& mesh) : mesh_(mesh) {}

  // Where the funnel wraps around a vertex, the path becomes a vertex point;
  // the next pass releases it to the vertex's narrower side, which may hold
  // a shortcut the strip did not. Passes stop when nothing shortens.
  std::vector<PathPoint> Run(std::vector<PathPoint> path) {
    double length = Length(path);
    for (int pass = 0; pass < 256 && path.size() >= 3; ++pass) {
      std::vector<PathPoint> straight;
      if (!Straighten(path, &straight)) break;
      const double shorter = Length(straight);
      if (!(shorter < length * (1 - 1e-14))) break;
      path = std::move(straight);
      length = shorter;
      // Without vertex points to release, another pass builds the same strip.
      if (!HasInteriorVertexPoint(path)) break;
    }
    return path;
  }

 private:
  bool HasVertex(int32_t f, int32_t v) const {
    return mesh_.Vertex(f, 0) == v || mesh_.Vertex(f, 1) == v || mesh_.Vertex(f, 2) == v;
  }

  Support SupportOf(const SurfacePoint& p) const {
    Support s;
    for (int i = 0; i < 3; ++i) {
      if (p.w[i] > kZero) {
        s.vertex[s.count] = mesh_.Vertex(p.face, i);
        s.weight[s.count] = p.w[i];
        ++s.count;
      }
    }
    return s;
  }
  bool FaceHolds(int32_t f, const Support& s) const {
    for (int i = 0; i < s.count; ++i) {
      if (!HasVertex(f, s.vertex[i])) return false;
    }
    return true;
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
  static bool HasInteriorVertexPoint(const std::vector<PathPoint>& path) {
    for (size_t i = 1; i + 1 < path.size(); ++i) {
      const std::array<double, 3>& w = path[i].point.w;
      if (w[0] == 1 || w[1] == 1 || w[2] == 1) return true;
    }
    return false;
  }
  static double Length(const std::vector<PathPoint>& path) {
    double length = 0;
    for (size_t i = 1; i < path.size(); ++i)
      length += (path[i].position - path[i - 1].position).norm();
    return length;
  }

  // Unfolded face: its vertex ids and their planar positions.
  struct Flat {
    int32_t face;
    std::array<int32_t, 3> v;
    std::array<Vec2, 3> p;
    Vec2 At(int32_t vertex) const {
      for (int i = 0; i < 3; ++i) {
        if (v[i] == vertex) return p[i];
      }
      return p[0];
    }
  };

  Flat FirstFlat(int32_t f) const {
    Flat flat{f, {mesh_.Vertex(f, 0), mesh_.Vertex(f, 1), mesh_.Vertex(f, 2)}, {}};
    const mesh::Vec3 a = mesh_.Position(flat.v[0]), e1 = mesh_.Position(flat.v[1]) - a,
                     e2 = mesh_.Position(flat.v[2]) - a;
    const double l = e1.norm();
    const double cx = e1.dot(e2) / l;
    const double cy = std::sqrt(std::max(e2.squaredNorm() - cx * cx, 0.0));
    flat.p = {Vec2{0, 0}, Vec2{l, 0}, Vec2{cx, cy}};
    return flat;
  }

  // Face g unfolded across its edge (a, b) shared with `prev`, on the other
  // side of that edge from prev's third vertex.
  Flat NextFlat(const Flat& prev, int32_t g, int32_t a, int32_t b) const {
    Flat flat{g, {mesh_.Vertex(g, 0), mesh_.Vertex(g, 1), mesh_.Vertex(g, 2)}, {}};
    const Vec2 pa = prev.At(a), pb = prev.At(b);
    int32_t c = -1, behind = -1;
    for (int i = 0; i < 3; ++i) {
      if (flat.v[i] != a && flat.v[i] != b) c = flat.v[i];
      if (prev.v[i] != a && prev.v[i] != b) behind = prev.v[i];
    }
    const double l = (mesh_.Position(b) - mesh_.Position(a)).norm();
    const double da = (mesh_.Position(c) - mesh_.Position(a)).norm(),
                 db = (mesh_.Position(c) - mesh_.Position(b)).norm();
    double x, y;
    geometry::Place(l, da, db, &x, &y);
    const Vec2 ux = (pb - pa) * (1 / l);
    Vec2 uy{-ux.y, ux.x};
    if (Cross(pb - pa, prev.At(behind) - pa) > 0) uy = uy * -1;  // away from prev
    const Vec2 pc = pa + ux * x + uy * y;
    for (int i = 0; i < 3; ++i) flat.p[i] = flat.v[i] == a ? pa : flat.v[i] == b ? pb : pc;
    return flat;
  }

  Vec2 Place(const Flat& flat, const Support& s) const {
    Vec2 out{0, 0};
    for (int i = 0; i < s.count; ++i) out = out + flat.At(s.vertex[i]) * s.weight[i];
    return out;
  }

  struct Portal {
    Vec2 left, right;
    int32_t left_id, right_id;  // mesh vertices; -1 for the ends
    int32_t face;               // the face before the portal (holds both ends)
  };
  // An apex of the funnel: an index into the portals and a side (0 start or
  // end, +1 left, -1 right).
  struct Apex {
    size_t portal;
    int side;
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

  double AngleAt(int32_t f, int32_t v) const {
    int k = 0;
    while (mesh_.Vertex(f, k) != v) ++k;
    const mesh::Vec3 a = mesh_.Position(mesh_.Vertex(f, (k + 1) % 3)) - mesh_.Position(v),
                     b = mesh_.Position(mesh_.Vertex(f, (k + 2) % 3)) - mesh_.Position(v);
    return std::atan2(a.cross(b).norm(), a.dot(b));
  }

  // The faces around v strictly after `from` up to `to`, on the side whose
  // angle at v is smaller (the side a shortest path hugs). False if neither
  // side connects them (boundary on both).
  bool Fan(int32_t v, int32_t from, int32_t to, Small<int32_t>* fan) const {
    double best = std::numeric_limits<double>::infinity();
    for (int dir = 0; dir < 2; ++dir) {
      Small<int32_t> faces;
      double angle = 0;
      int32_t f = from;
      for (int guard = 0; guard < MeshView::kMaxFanSteps && f != to; ++guard) {
        f = mesh_.Turn(f, v, dir);
        if (f < 0 || f == from) break;
        faces.push_back(f);
        if (f != to) angle += AngleAt(f, v);
      }
      if (f == to && angle < best) {
        best = angle;
        *fan = std::move(faces);
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
    Small<std::array<int32_t, 2>> edges;
    if (!BuildStrip(support, seg, &strip, &edges)) return false;
    Small<Portal> portals;
    Vec2 start, end;
    if (!UnfoldStrip(strip, edges, support, &portals, &start, &end)) return false;
    return Rebuild(run, portals, Funnel(portals, start), start, end, out);
  }

  // Segment faces: segment i (run[i] -> run[i+1]) lies in face (*seg)[i].
  // False if a segment lies in no face.
  bool SegmentFaces(const std::vector<PathPoint>& run, const Small<Support>& support,
                    Small<int32_t>* seg_out) const {
    const size_t k = run.size();
    Small<int32_t>& seg = *seg_out;
    for (size_t i = 0; i + 1 < k; ++i) {
      for (int32_t f : FacesOf(run[i].point, support[i])) {
        if (FaceHolds(f, support[i + 1])) {
          seg[i] = f;
          break;
        }
      }
      if (seg[i] < 0) return false;
    }
    return true;
  }

  // The strip: faces in order (*strip starts with the first segment's face)
  // and the edges (portals) between them. False if the path does not cross
  // from face to face over shared edges or round a vertex.
  bool BuildStrip(const Small<Support>& support, const Small<int32_t>& seg,
                  Small<int32_t>* strip_out, Small<std::array<int32_t, 2>>* edges_out) const {
    const size_t k = support.size();
    Small<int32_t>& strip = *strip_out;
    Small<std::array<int32_t, 2>>& edges = *edges_out;
    // Entering the face just left (back across the same edge) cancels out.
    auto push = [&](int32_t face, std::array<int32_t, 2> edge) {
      if (strip.size() >= 2 && strip[strip.size() - 2] == face) {
        strip.pop_back();
        edges.pop_back();
      } else {
        strip.push_back(face);
        edges.push_back(edge);
      }
    };
    for (size_t i = 1; i + 1 < k; ++i) {
      const int32_t prev = strip.back(), next = seg[i];
      if (next == prev) continue;
      if (support[i].count == 2) {
        const int32_t a = support[i].vertex[0], b = support[i].vertex[1];
        if (Across(prev, a, b) != next) return false;
        push(next, {a, b});
      } else if (support[i].count == 1) {
        const int32_t v = support[i].vertex[0];
        Small<int32_t> fan;
        if (!Fan(v, prev, next, &fan)) return false;
        for (int32_t f : fan) {
          const int32_t from = strip.back();
          int32_t u = -1;  // the other end of the edge shared with f
          for (int c = 0; c < 3; ++c) {
            if (mesh_.Vertex(from, c) != v && HasVertex(f, mesh_.Vertex(from, c)))
              u = mesh_.Vertex(from, c);
          }
          if (u < 0) return false;
          push(f, {v, u});
        }
      } else {
        return false;
      }
    }
    if (strip.size() > 1 && strip.back() != seg[k - 2]) return false;
    return true;
  }

  // Unfolds the strip and collects its portals, the start and end points
  // first and last as degenerate portals. False if the end is not in the
  // strip's last face.
  bool UnfoldStrip(const Small<int32_t>& strip, const Small<std::array<int32_t, 2>>& edges,
                   const Small<Support>& support, Small<Portal>* portals_out, Vec2* start_out,
                   Vec2* end_out) const {
    const size_t k = support.size();
    Small<Portal>& portals = *portals_out;
    Vec2& start = *start_out;
    Vec2& end = *end_out;
    Small<Flat> flats = {FirstFlat(strip[0])};
    start = Place(flats[0], support[0]);
    const int32_t start_id = support[0].count == 1 ? support[0].vertex[0] : -1;
    portals.push_back({start, start, start_id, start_id, strip[0]});
    for (size_t i = 0; i < edges.size(); ++i) {
      const int32_t a = edges[i][0], b = edges[i][1];
      const Flat& prev = flats.back();
      int32_t behind = -1;
      for (int j = 0; j < 3; ++j) {
        if (prev.v[j] != a && prev.v[j] != b) behind = prev.v[j];
      }
      Portal portal{prev.At(a), prev.At(b), a, b, prev.face};
      // (behind, right, left) counter-clockwise: left is on the left of travel.
      if (Cross(portal.left - prev.At(behind), portal.right - prev.At(behind)) > 0) {
        std::swap(portal.left, portal.right);
        std::swap(portal.left_id, portal.right_id);
      }
      portals.push_back(portal);
      flats.push_back(NextFlat(prev, strip[i + 1], a, b));
    }
    end = Place(flats.back(), support[k - 1]);
    if (!FaceHolds(flats.back().face, support[k - 1])) return false;
    const int32_t end_id = support[k - 1].count == 1 ? support[k - 1].vertex[0] : -1;
    portals.push_back({end, end, end_id, end_id, flats.back().face});
    return true;
  }

  // The funnel: the apexes of the shortest path through the portals, from
  // the start (portal 0) to the end (the last portal).
  Small<Apex> Funnel(const Small<Portal>& portals, const Vec2& start) const {
    Small<Apex> apexes = {{0, 0}};
    Vec2 apex = start, left = start, right = start;
    size_t apex_index = 0, left_index = 0, right_index = 0;
    const size_t n = portals.size();
    for (size_t i = 1; i < n; ++i) {
      const Vec2 l = portals[i].left, r = portals[i].right;
      // Tighten the right side.
      if (Cross(right - apex, r - apex) >= 0) {
        if ((apex.x == right.x && apex.y == right.y) || Cross(left - apex, r - apex) < 0) {
          right = r;
          right_index = i;
        } else {
          apexes.push_back({left_index, +1});
          apex = right = left;
          apex_index = right_index = left_index;
          i = apex_index;
          continue;
        }
      }
      // Tighten the left side.
      if (Cross(left - apex, l - apex) <= 0) {
        if ((apex.x == left.x && apex.y == left.y) || Cross(right - apex, l - apex) > 0) {
          left = l;
          left_index = i;
        } else {
          apexes.push_back({right_index, -1});
          apex = left = right;
          apex_index = left_index = right_index;
          i = apex_index;
          continue;
        }
      }
    }
    // The end itself may have become an apex (one side of the last portal).
    if (apexes.back().portal == n - 1) apexes.pop_back();
    apexes.push_back({n - 1, 0});

    return apexes;
  }

  // Rebuild the path: the crossings of each straight section with the
  // portals it passes, and the apexes as vertex points. False on a
  // degenerate crossing or an apex that is not a mesh vertex.
  bool Rebuild(const std::vector<PathPoint>& run, const Small<Portal>& portals,
               const Small<Apex>& apexes, const Vec2& start, const Vec2& end,
               std::vector<PathPoint>* out) const {
    auto apex_point = [&](const Apex& a) -> Vec2 {
      return a.side > 0 ? portals[a.portal].left : portals[a.portal].right;
    };
    auto apex_vertex = [&](const Apex& a) -> int32_t {
      return a.side >= 0 ? portals[a.portal].left_id : portals[a.portal].right_id;
    };
    out->assign({run[0]});
    for (size_t s = 0; s + 1 < apexes.size(); ++s) {
      const Apex a = apexes[s], b = apexes[s + 1];
      const Vec2 pa = s == 0 ? start : apex_point(a);
      const Vec2 pb = s + 2 == apexes.size() ? end : apex_point(b);
      const int32_t va = apex_vertex(a), vb = apex_vertex(b);
      for (size_t j = a.portal + 1; j < b.portal; ++j) {
        const Portal& portal = portals[j];
        if ((va >= 0 && (portal.left_id == va || portal.right_id == va)) ||
            (vb >= 0 && (portal.left_id == vb || portal.right_id == vb))) {
          continue;  // the section passes through this portal's end
        }
        const Vec2 dir = pb - pa;
        const double denom = Cross(dir, portal.left - portal.right);
        if (denom == 0) return false;
        const double t = std::clamp(Cross(dir, pa - portal.right) / denom, 0.0, 1.0);
        SurfacePoint point{portal.face, {0, 0, 0}};
        for (int c = 0; c < 3; ++c) {
          const int32_t v = mesh_.Vertex(portal.face, c);
          if (v == portal.right_id) point.w[c] = 1 - t;
          if (v == portal.left_id) point.w[c] = t;
        }
        out->push_back({point, (1 - t) * mesh_.Position(portal.right_id) +
                                   t * mesh_.Position(portal.left_id)});
      }
      if (s + 2 < apexes.size()) {
        if (vb < 0) return false;
        SurfacePoint point{portals[b.portal].face, {0, 0, 0}};
        for (int c = 0; c < 3; ++c) {
          if (mesh_.Vertex(point.face, c) == vb) point.w[c] = 1;
        }
        out->push_back({point, mesh_.Position(vb)});
      }
    }
    out->push_back(run.back());
    return true;
  }

 public:
  // The length of the straight path through the strip of faces `run`
  // crosses; nullopt when the funnel wraps round a strip vertex or the run
  // is not a proper strip.
  std::optional<double> StraightLength(const std::vector<PathPoint>& run) const {
    const size_t k = run.size();
    if (k < 3)
      return k == 2 ? std::optional((run[1].position - run[0].position).norm()) : std::nullopt;
    Small<Support> support(k);
    for (size_t i = 0; i < k; ++i) support[i] = SupportOf(run[i].point);
    Small<int32_t> seg(k - 1, -1);
    if (!SegmentFaces(run, support, &seg)) return std::nullopt;
    Small<int32_t> strip = {seg[0]};
    Small<std::array<int32_t, 2>> edges;
    if (!BuildStrip(support, seg, &strip, &edges)) return std::nullopt;
    Small<Portal> portals;
    Vec2 start, end;
    if (!UnfoldStrip(strip, edges, support, &portals, &start, &end)) return std::nullopt;
    if (Funnel(portals, start).size() != 2) return std::nullopt;
    const Vec2 d = end - start;
    return std::sqrt(d.x * d.x + d.y * d.y);
  }

 private:
  const MeshView& mesh_;
};

}  // namespace

std::optional<double> StraightLength(const MeshView& mesh, const std::vector<PathPoint>& path) {
  return Straightener(mesh).StraightLength(path);
}

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

double PathLength(const std::vector<PathPoint>& path) {
  double sum = 0;
  for (size_t i = 1; i < path.size(); ++i) sum += (path[i].position - path[i - 1].position).norm();
  return sum;
}

}  // namespace geodex::query
