#include "core/query/internal/chord_walk.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "absl/container/inlined_vector.h"
#include "core/geometry/planar_unfolding.h"
#include "core/query/internal/path_straightening.h"

namespace geodex::query {
namespace {

using mesh::Vec3;

// The barycentric velocity (sum 0) of moving along `dir` in face f.
std::array<double, 3> Velocity(const MeshView& view, int32_t f, const Vec3& dir) {
  const Vec3 v[3] = {view.Position(view.Vertex(f, 0)), view.Position(view.Vertex(f, 1)),
                     view.Position(view.Vertex(f, 2))};
  const Vec3 n = (v[1] - v[0]).cross(v[2] - v[0]);
  const double area2 = n.squaredNorm();
  std::array<double, 3> beta;
  for (int i = 0; i < 3; ++i) beta[i] = n.cross(v[(i + 2) % 3] - v[(i + 1) % 3]).dot(dir) / area2;
  return beta;
}

// Direction `d`, in the plane of the face across edge (a, b) from face f,
// turned about that edge into f's plane: a straight line across the edge
// in the unfolding of the two faces.
Vec3 UnfoldHeading(const MeshView& view, int32_t f, const std::array<int32_t, 2>& edge,
                   const Vec3& d) {
  const Vec3 a = view.Position(edge[0]);
  const Vec3 e = (view.Position(edge[1]) - a).normalized();
  Vec3 into = Vec3::Zero();  // in f's plane, perpendicular to the edge, into f
  for (int i = 0; i < 3; ++i) {
    const int32_t c = view.Vertex(f, i);
    if (c != edge[0] && c != edge[1]) {
      into = view.Position(c) - a;
      into -= into.dot(e) * e;
    }
  }
  const double along = d.dot(e);
  return along * e + (d - along * e).norm() * into.normalized();
}

// True when every vertex `p` has weight on (weight > 1e-12) is a vertex of f.
bool FaceHolds(const MeshView& view, int32_t f, const SurfacePoint& p) {
  for (int i = 0; i < 3; ++i) {
    if (p.w[i] > 1e-12 && view.Corner(f, view.Vertex(p.face, i)) < 0) return false;
  }
  return true;
}

// A corridor of faces (consecutive ones share an edge) unfolded into one
// plane, with the points it runs between. The shortest path through it is
// found by the funnel algorithm on the unfolded edges it crosses
// (portals), in a few flops a face; where that path bends round a vertex
// short of a straight angle on the vertex's other side, the corridor is
// moved to that side (Release).
class Corridor {
 public:
  using Vec2 = Eigen::Vector2d;
  // Where the funnel's path bends: the vertex, the run of portals
  // [first, last] that end at it on the side it is on, and the angle the
  // path turns by.
  struct Bend {
    int32_t vertex;
    size_t first, last;
    double turn;
  };
  using Bends = absl::InlinedVector<Bend, 8>;

  std::vector<int32_t>& faces() { return faces_; }

  // Unfolds faces() from `from` (a point faces()[0] holds) to `to` (one the
  // last face holds). False when consecutive faces share no edge.
  bool Unfold(const MeshView& view, const SurfacePoint& from, const SurfacePoint& to) {
    portals_.clear();
    ids_.clear();
    const int32_t f0 = faces_[0];
    const Vec3 a = view.Position(view.Vertex(f0, 0));
    const Vec3 e1 = view.Position(view.Vertex(f0, 1)) - a;
    const Vec3 e2 = view.Position(view.Vertex(f0, 2)) - a;
    const double l = e1.norm(), cx = e1.dot(e2) / l;
    // Counterclockwise, as every face of the oriented mesh then is.
    corner_[0] = Vec2::Zero();
    corner_[1] = Vec2(l, 0);
    corner_[2] = Vec2(cx, std::sqrt(std::max(e2.squaredNorm() - cx * cx, 0.0)));
    start_ = At(view, f0, from);
    for (size_t t = 0; t + 1 < faces_.size(); ++t) {
      const int32_t f = faces_[t];
      int edge = -1;
      for (int i = 0; i < 3; ++i) {
        const int32_t h = view.twins[3 * f + i];
        if (h >= 0 && h / 3 == faces_[t + 1]) edge = i;
      }
      if (edge < 0) return false;
      Cross(view, f, edge, view.twins[3 * f + edge]);
    }
    end_ = At(view, faces_.back(), to);
    return true;
  }

  // |end - start| when that segment passes through every portal.
  std::optional<double> StraightLength() const {
    const Vec2 d = end_ - start_;
    const double slack = 1e-12 * d.squaredNorm();
    for (const auto& [p, q] : portals_) {
      const double sp = Cross2(d, p - start_), sq = Cross2(d, q - start_);
      if (std::min(sp, sq) > slack || std::max(sp, sq) < -slack) return std::nullopt;
    }
    return d.norm();
  }

  // The length of the shortest path through the corridor (the funnel
  // algorithm, Lee & Preparata 1984) and where it bends.
  double Funnel(Bends* bends) const {
    const size_t n = portals_.size();
    auto end_of = [&](size_t i, int side) { return i < n ? portals_[i][side] : end_; };
    absl::InlinedVector<Vec2, 8> apexes = {start_};
    bends->clear();
    Vec2 apex = start_, side_at[2] = {end_of(0, 0), end_of(0, 1)};
    size_t index[2] = {0, 0};
    for (size_t i = 1; i <= n; ++i) {
      // Side 1 (right) narrows when the new end is left of the apex's ray
      // to it, side 0 (left) when it is right; crossing the other side's
      // ray, the path bends round that side's end.
      for (int side : {1, 0}) {
        const double sign = side == 1 ? 1 : -1;
        const Vec2 next = end_of(i, side);
        if (sign * Cross2(side_at[side] - apex, next - apex) < 0) continue;  // widens
        const int other = 1 - side;
        if (apex == side_at[side] || sign * Cross2(side_at[other] - apex, next - apex) < 0) {
          side_at[side] = next;
          index[side] = i;
          continue;
        }
        const size_t at = index[other];
        if (at == n) break;  // the other side's end is the end point
        apex = side_at[other];
        apexes.push_back(apex);
        const int32_t v = ids_[at][other];
        size_t first = at, last = at;
        while (first > 0 && ids_[first - 1][other] == v) --first;
        while (last + 1 < n && ids_[last + 1][other] == v) ++last;
        bends->push_back({v, first, last, 0});
        side_at[0] = side_at[1] = apex;
        index[0] = index[1] = i = at;
        break;
      }
    }
    apexes.push_back(end_);
    double length = 0;
    for (size_t k = 1; k < apexes.size(); ++k) {
      const Vec2 d = apexes[k] - apexes[k - 1];
      length += d.norm();
      if (k + 1 < apexes.size()) {
        const Vec2 e = apexes[k + 1] - apexes[k];
        (*bends)[k - 1].turn = std::atan2(std::abs(Cross2(d, e)), d.dot(e));
      }
    }
    return length;
  }

  // Moves the corridor to the other side of the bend's vertex: the faces
  // holding it between the bend's portals are replaced by those round the
  // vertex the other way. False at the boundary.
  bool Release(const MeshView& view, const Bend& bend) {
    const int32_t v = bend.vertex;
    const int32_t from = faces_[bend.first], to = faces_[bend.last + 1];
    const int32_t skip = faces_[bend.first + 1];
    int dir = view.Turn(from, v, 0) == skip ? 1 : 0;
    absl::InlinedVector<int32_t, 16> round;
    int32_t g = from;
    for (int step = 0; step < MeshView::kMaxFanSteps; ++step) {
      g = view.Turn(g, v, dir);
      if (g < 0 || g == from) return false;
      if (g == to) break;
      round.push_back(g);
    }
    if (g != to) return false;
    faces_.erase(faces_.begin() + bend.first + 1, faces_.begin() + bend.last + 1);
    faces_.insert(faces_.begin() + bend.first + 1, round.begin(), round.end());
    return true;
  }

 private:
  static double Cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

  // Steps from face f over its edge `edge` (from corner edge to edge + 1)
  // into the face of the twin half-edge h: the portal, then h's face's
  // third corner unfolded on the far side of the edge.
  void Cross(const MeshView& view, int32_t f, int edge, int32_t h) {
    const int i1 = edge, i2 = (edge + 1) % 3, behind = (edge + 2) % 3;
    const Vec2 a = corner_[i2], b = corner_[i1];  // left and right going out
    portals_.push_back({a, b});
    ids_.push_back({view.Vertex(f, i2), view.Vertex(f, i1)});
    const int32_t g = h / 3, k = (h % 3 + 2) % 3;  // h runs from f's corner i2 to i1
    const Vec3 c = view.Position(view.Vertex(g, k));
    const double l = (b - a).norm();
    double x, y;
    geometry::Place(l, (c - view.Position(view.Vertex(f, i2))).norm(),
                    (c - view.Position(view.Vertex(f, i1))).norm(), &x, &y);
    const Vec2 ux = (b - a) / l;
    Vec2 uy(-ux.y(), ux.x());
    if (Cross2(ux, corner_[behind] - a) > 0) uy = -uy;  // away from f
    corner_[h % 3] = a;
    corner_[(h % 3 + 1) % 3] = b;
    corner_[k] = a + x * ux + y * uy;
  }
  // Point p (whose weighted vertices face f holds) in the plane.
  Vec2 At(const MeshView& view, int32_t f, const SurfacePoint& p) const {
    Vec2 out = Vec2::Zero();
    for (int i = 0; i < 3; ++i) {
      if (p.w[i] > 0) out += p.w[i] * corner_[std::max(0, view.Corner(f, view.Vertex(p.face, i)))];
    }
    return out;
  }

  std::vector<int32_t> faces_;
  Vec2 corner_[3];  // of the face last unfolded
  absl::InlinedVector<std::array<Vec2, 2>, 32> portals_;
  absl::InlinedVector<std::array<int32_t, 2>, 32> ids_;  // the portals' vertices
  Vec2 start_ = Vec2::Zero(), end_ = Vec2::Zero();
};

// A corridor from `from` to `to` found without the distance field: from
// face to face, each step heading for `to` along the chord projected into
// the face (past a ridge, where that points back, straight on across the
// edge), until a face holds `to`. The faces go to *faces. False when the
// walk reaches a vertex, the boundary or a dead end, crosses more than
// `max_steps` faces or walks more than twice the chord; then the caller
// traces instead.
bool WalkCorridor(const MeshView& view, const PathPoint& from, const PathPoint& to, int max_steps,
                  std::vector<int32_t>* faces) {
  // The face to start in: from's face, or, for a vertex or edge point, the
  // face round it that the chord enters.
  absl::InlinedVector<int32_t, 16> starts;
  int positive = 0, heaviest = 0;
  for (int i = 0; i < 3; ++i) {
    positive += from.point.w[i] > 1e-12;
    if (from.point.w[i] > from.point.w[heaviest]) heaviest = i;
  }
  if (positive == 3) {
    starts.push_back(from.point.face);
  } else {
    view.FacesAround(view.Vertex(from.point.face, heaviest), from.point.face, &starts);
  }
  int32_t f = -1;
  std::array<double, 3> w;
  for (int32_t g : starts) {
    if (!FaceHolds(view, g, from.point)) continue;
    std::array<double, 3> b = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
      const int c = view.Corner(g, view.Vertex(from.point.face, i));
      if (c >= 0) b[c] = from.point.w[i];  // FaceHolds: the others weigh ~0
    }
    if (FaceHolds(view, g, to.point)) {
      faces->assign({g});
      return true;
    }
    const std::array<double, 3> beta = Velocity(view, g, to.position - from.position);
    const double eps = 1e-12 * (std::abs(beta[0]) + std::abs(beta[1]) + std::abs(beta[2]));
    bool enters = eps > 0;
    for (int i = 0; i < 3; ++i) enters = enters && (b[i] > 1e-12 || beta[i] > eps);
    if (enters) {
      f = g;
      w = b;
      break;
    }
  }
  if (f < 0) return false;
  faces->assign({f});
  Vec3 x = from.position;
  // A walk that wanders (round a feature, or circling `to`) gives up early.
  const double max_length = 2 * (to.position - from.position).norm();
  double length = 0;
  Vec3 heading = Vec3::Zero();  // the last step, and the edge it crossed
  std::array<int32_t, 2> heading_edge = {-1, -1};
  for (int step = 0; step < max_steps && length <= max_length; ++step) {
    if (FaceHolds(view, f, to.point)) return true;
    std::array<double, 3> beta = Velocity(view, f, to.position - x);
    double t;
    int exit = DescentExit(beta, w, &t);
    if ((exit < 0 || !(t > 1e-14)) && heading.squaredNorm() > 0) {
      // Past a ridge the chord points back: go on straight, the heading of
      // the face before unfolded into this one.
      beta = Velocity(view, f, UnfoldHeading(view, f, heading_edge, heading));
      exit = DescentExit(beta, w, &t);
    }
    if (exit < 0 || !(t > 1e-14)) return false;
    for (int i = 0; i < 3; ++i) w[i] = std::max(w[i] + t * beta[i], 0.0);
    w[exit] = 0;
    const double sum = w[0] + w[1] + w[2];
    for (double& c : w) c /= sum;
    if (w[0] > 1 - 1e-9 || w[1] > 1 - 1e-9 || w[2] > 1 - 1e-9) return false;
    const Vec3 last = x;
    x = w[0] * view.Position(view.Vertex(f, 0)) + w[1] * view.Position(view.Vertex(f, 1)) +
        w[2] * view.Position(view.Vertex(f, 2));
    length += (x - last).norm();
    const int32_t g = view.twins[3 * f + (exit + 1) % 3];  // the edge opposite `exit`
    if (g < 0) return false;
    heading = x - last;
    heading_edge = {view.Vertex(f, (exit + 1) % 3), view.Vertex(f, (exit + 2) % 3)};
    f = g / 3;
    faces->push_back(f);
    w = AcrossEdge(g, exit, w);
  }
  return false;
}

// The angle of face g at its vertex v.
double CornerAngle(const MeshView& view, int32_t g, int32_t v) {
  const int k = view.Corner(g, v);
  const Vec3 o = view.Position(v);
  const Vec3 a = view.Position(view.Vertex(g, (k + 1) % 3)) - o;
  const Vec3 b = view.Position(view.Vertex(g, (k + 2) % 3)) - o;
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// A path through a vertex is locally shortest when the surface angle on
// either side of it is at least pi (Mitchell, Mount & Papadimitriou 1987),
// so when it turns by at most the vertex's angle excess (sum - 2 pi), to
// rounding.
constexpr double kBendSlack = 1e-9;

// The sum of the angles at vertex v of the faces round it (`face` is one);
// nullopt at the boundary.
std::optional<double> AngleSum(const MeshView& view, int32_t face, int32_t v) {
  double total = 0;
  int32_t g = face;
  for (int step = 0; step < MeshView::kMaxFanSteps; ++step) {
    total += CornerAngle(view, g, v);
    g = view.Turn(g, v, 0);
    if (g < 0) return std::nullopt;
    if (g == face) return total;
  }
  return std::nullopt;
}

}  // namespace

std::optional<NearPath> NearPathLength(const MeshView& view, const GradientPaths& paths,
                                       const SurfacePoint& from, const SurfacePoint& to,
                                       bool walk_chord, double plausible) {
  // First the corridors of the chord, from either end, unfolded into the
  // plane. A straight segment through the corridor is a local geodesic, as
  // the straightened trace would be, found without evaluating the distance
  // field, so at a fraction of the trace's cost. Else the funnel's path
  // through it, released from the vertices it bends round short of a
  // straight angle on their other side: one that then bends at no vertex,
  // or at one saddle by no more than its angle excess, is a local geodesic
  // too. Paths bending at several saddles were often in a wrong corridor,
  // and so, rarely, is a straight one longer than `plausible` (across a
  // sharp feature); then the trace decides. Every candidate is a surface
  // path, so the shortest is kept (figures: tests/bench/README.md).
  constexpr int kMaxWalkSteps = 256;
  // A release shortens the path; a near path passes few vertices.
  constexpr int kMaxReleases = 8;
  const PathPoint ends[2] = {{from, view.PositionOf(from)}, {to, view.PositionOf(to)}};
  std::optional<double> doubted;
  auto doubt = [&](double length) { doubted = std::min(length, doubted.value_or(length)); };
  std::optional<NearPath> found;
  Corridor corridor;
  Corridor::Bends bends;
  for (int start = 0; start < (walk_chord ? 2 : 0); ++start) {
    const SurfacePoint& a = ends[start].point;
    const SurfacePoint& b = ends[1 - start].point;
    if (!WalkCorridor(view, ends[start], ends[1 - start], kMaxWalkSteps, &corridor.faces()) ||
        !corridor.Unfold(view, a, b)) {
      continue;
    }
    if (const std::optional<double> length = corridor.StraightLength()) {
      if (*length <= plausible) return NearPath{*length, false};
      doubt(*length);
      continue;
    }
    for (int release = 0; release <= kMaxReleases; ++release) {
      const double length = corridor.Funnel(&bends);
      const Corridor::Bend* shortcut = nullptr;
      bool judged = true;
      for (const Corridor::Bend& bend : bends) {
        const std::optional<double> angle =
            AngleSum(view, corridor.faces()[bend.first], bend.vertex);
        if (!angle) {
          judged = false;  // a boundary vertex
          break;
        }
        if (bend.turn > *angle - 2 * M_PI + kBendSlack) {
          shortcut = &bend;
          break;
        }
      }
      if (!judged) break;
      if (shortcut == nullptr) {
        if (length <= plausible && bends.size() <= 1) {
          // Straight in the walk's own corridor: as sure as a straight walk.
          if (release == 0 && bends.empty()) return NearPath{length, false};
          // Else a local geodesic in a corridor the walk did not find by
          // itself: kept, but the other walk may find a shorter one.
          if (!found || length < found->length) found = NearPath{length, !bends.empty()};
        } else {
          doubt(length);
        }
        break;
      }
      if (!corridor.Release(view, *shortcut) || !corridor.Unfold(view, a, b)) break;
    }
  }
  // Every candidate is a surface path: the shortest is the closest.
  if (found) {
    if (doubted && *doubted < found->length) return NearPath{*doubted, true};
    return found;
  }
  // Without Path's restarts, which double the cost of a near pair for a
  // small gain (tests/bench/README.md).
  const absl::StatusOr<std::vector<PathPoint>> path =
      paths.Shortest(from, to, GradientPaths::Search::kNearPair);
  if (path.ok()) {
    const double length = PathLength(*path);
    if (!doubted || length <= *doubted) return NearPath{length, WrapsRoundAVertex(*path)};
  }
  if (doubted) return NearPath{*doubted, true};
  return std::nullopt;
}

}  // namespace geodex::query
