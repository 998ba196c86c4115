// Geodesic paths by tracing the gradient of the approximate distance field
// (paper §6.2): QueryEngine::Path.

#include <algorithm>
#include <cmath>
#include <optional>
#include <queue>
#include <unordered_map>

#include "absl/container/flat_hash_map.h"
#include "absl/container/inlined_vector.h"
#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/geometry/unfolding.h"
#include "core/query/path_straightening.h"
#include "core/query/query_engine.h"

namespace geodex::query {
namespace {

using mesh::Vec3;

struct Tracer {
  const QueryEngine& engine;
  const MeshView& mesh;
  LiftedPoint source;
  absl::flat_hash_map<int32_t, double> cache;

  // Approximate distance from the source to vertex v (O(1), memoised).
  double D(int32_t v) {
    auto [it, inserted] = cache.try_emplace(v, 0.0);
    if (inserted) {
      const index::VertexRecord& r = engine.index().vertices()[v];
      LiftedPoint x;
      x.triangle = r.triangle;
      for (int c = 0; c < 3; ++c) {
        x.corner[c] = r.corner[c];
        x.distance[c] = r.distance[c];
      }
      it->second = engine.LiftedDistance(source, x);
    }
    return it->second;
  }

  // Direction of descent of the distance field in face f at barycentric
  // position b, as barycentric velocities (sum 0), and its slope. The three
  // vertex distances fix an unfolded source in the face's plane
  // (trilateration); the path heads straight for it, which is exact where the
  // field is planar. When the distances do not fit a point (|residual| large)
  // the gradient of their linear interpolant is used instead.
  std::array<double, 3> Descent(int32_t f, const std::array<double, 3>& b, double* magnitude) {
    const Vec3 v[3] = {mesh.Position(mesh.Vertex(f, 0)), mesh.Position(mesh.Vertex(f, 1)),
                       mesh.Position(mesh.Vertex(f, 2))};
    const double d[3] = {D(mesh.Vertex(f, 0)), D(mesh.Vertex(f, 1)), D(mesh.Vertex(f, 2))};
    const Vec3 e1 = v[1] - v[0], e2 = v[2] - v[0];
    const Vec3 n = e1.cross(e2);
    const double area2 = n.squaredNorm();
    Vec3 grad_b[3];
    for (int i = 0; i < 3; ++i) grad_b[i] = n.cross(v[(i + 2) % 3] - v[(i + 1) % 3]) / area2;
    Vec3 dir;
    const double l = e1.norm();
    const Vec3 ux = e1 / l;
    const Vec3 uy = n.cross(e1).normalized();
    const double cx = e2.dot(ux), cy = e2.dot(uy);
    bool planar = false;
    if (cy > 1e-6 * l) {
      double sx, sy;
      geometry::Trilaterate(l, cx, cy, d[0], d[1], d[2], &sx, &sy);
      const double r0 = std::sqrt(sx * sx + sy * sy);
      planar = std::abs(r0 - d[0]) < 1e-3 * (d[0] + l);
      if (planar) {
        const Vec3 source = v[0] + sx * ux + sy * uy;
        const Vec3 x = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
        dir = source - x;
      }
    }
    if (!planar) {
      dir = -(d[0] * grad_b[0] + d[1] * grad_b[1] + d[2] * grad_b[2]);
    }
    *magnitude = dir.norm();
    return {grad_b[0].dot(dir), grad_b[1].dot(dir), grad_b[2].dot(dir)};
  }

  // Faces around vertex v, starting from face f.
  std::vector<int32_t> FacesAround(int32_t v, int32_t f) const {
    std::vector<int32_t> out;
    mesh.FacesAround(v, f, &out);
    return out;
  }
};

// Path restarts are tried when the straightened path is longer than the
// approximate distance by more than this factor: above the approximate
// distance's usual error, below the excess of a path in a wrong corridor
// (figures: tests/bench/README.md).
constexpr double kPathRestartRatio = 1.01;

// True when a point strictly inside the path is a mesh vertex: there the
// funnel of StraightenPath wrapped round the vertex.
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

// TracePath's fallback: from vertex v (a vertex of face f) along mesh edges to
// a vertex of the face holding the source, by A* with the straight-line
// distance to the source as heuristic, then straight to the source (`source`,
// the point at `from`). Appends to `path` (traced from the target) and returns
// it reversed, source first.
template <typename VertexPoint>
absl::StatusOr<std::vector<PathPoint>> FinishOnGraph(
    Tracer& tr, const MeshView& view, const SurfacePoint& from, const PathPoint& source,
    const VertexPoint& vertex_point, std::vector<PathPoint>& path, int32_t v, int32_t f) {
  const Vec3 goal = source.position;
  if (path.back().position != view.Position(v)) path.push_back(vertex_point(f, v));
  struct Node {
    double g;
    int32_t face;  // a face containing the vertex and its parent
    int32_t parent;
  };
  std::unordered_map<int32_t, Node> seen;
  using Item = std::pair<double, int32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  seen[v] = {0, f, -1};
  open.push({(view.Position(v) - goal).norm(), v});
  int32_t reached = -1;
  while (!open.empty()) {
    const auto [key, u] = open.top();
    open.pop();
    const Node node = seen[u];
    if (key > node.g + (view.Position(u) - goal).norm() + 1e-12) continue;  // stale
    if (view.Corner(from.face, u) >= 0) {
      reached = u;
      break;
    }
    for (int32_t g : tr.FacesAround(u, node.face)) {
      for (int i = 0; i < 3; ++i) {
        const int32_t w = view.faces[3 * g + i];
        if (w == u) continue;
        const double cost = node.g + (view.Position(w) - view.Position(u)).norm();
        auto it = seen.find(w);
        if (it != seen.end() && it->second.g <= cost) continue;
        seen[w] = {cost, g, u};
        open.push({cost + (view.Position(w) - goal).norm(), w});
      }
    }
  }
  if (reached < 0) return absl::InternalError("no mesh path to the source");
  std::vector<PathPoint> tail;
  for (int32_t u = reached; u != v; u = seen[u].parent)
    tail.push_back(vertex_point(seen[u].face, u));
  path.insert(path.end(), tail.rbegin(), tail.rend());
  path.push_back(source);
  std::reverse(path.begin(), path.end());
  return path;
}

// The face round vertex v (starting from face f) to leave v by: the first
// holding the source, else the one where the descent from v points inside the
// face and is steepest; -1 if there is none.
template <typename ContainsSource>
int32_t FaceToLeaveVertex(Tracer& tr, const MeshView& view, int32_t v, int32_t f,
                          const ContainsSource& contains_source) {
  int32_t best_face = -1;
  double best_slope = 0;
  for (int32_t g : tr.FacesAround(v, f)) {
    if (contains_source(g)) {
      best_face = g;
      break;
    }
    double magnitude;
    const int k = view.Corner(g, v);
    std::array<double, 3> at = {0, 0, 0};
    at[k] = 1;
    const auto beta = tr.Descent(g, at, &magnitude);
    const double e = 1e-12 * (std::abs(beta[0]) + std::abs(beta[1]) + std::abs(beta[2]));
    if (beta[(k + 1) % 3] >= -e && beta[(k + 2) % 3] >= -e && beta[k] < -e &&
        magnitude > best_slope) {
      best_slope = magnitude;
      best_face = g;
    }
  }
  return best_face;
}

// The neighbour of vertex v (round v from face f) with the lowest distance,
// if lower than v's, and a face holding the edge to it; false if v is a local
// minimum of the approximate field.
bool LowerNeighbour(Tracer& tr, const MeshView& view, int32_t v, int32_t f, int32_t* next,
                    int32_t* next_face) {
  *next = -1;
  *next_face = -1;
  double lowest = tr.D(v);
  for (int32_t g : tr.FacesAround(v, f)) {
    for (int i = 0; i < 3; ++i) {
      const int32_t u = view.faces[3 * g + i];
      if (u != v && tr.D(u) < lowest) {
        lowest = tr.D(u);
        *next = u;
        *next_face = g;
      }
    }
  }
  return *next >= 0;
}

// Where the descent beta from barycentric position b leaves the face: the
// corner whose weight reaches 0 first (-1 if none decreases) and the step
// `t` to it.
int DescentExit(const std::array<double, 3>& beta, const std::array<double, 3>& b, double* t) {
  *t = std::numeric_limits<double>::infinity();
  int exit = -1;
  const double eps = 1e-12 * (std::abs(beta[0]) + std::abs(beta[1]) + std::abs(beta[2]));
  for (int i = 0; i < 3; ++i) {
    if (beta[i] < -eps) {
      const double ti = -b[i] / beta[i];
      if (ti < *t) {
        *t = ti;
        exit = i;
      }
    }
  }
  return exit;
}

// The vertex of face f with the lowest approximate distance (first on ties).
int32_t LowestVertex(Tracer& tr, const MeshView& view, int32_t f) {
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (tr.D(view.faces[3 * f + i]) < tr.D(view.faces[3 * f + k])) k = i;
  }
  return view.faces[3 * f + k];
}

// Barycentric weights `w` of a point on the edge of a face opposite its
// corner `exit`, re-expressed in the face across that edge, whose half-edge
// g (3 * face + corner) is the twin of the edge's.
std::array<double, 3> AcrossEdge(int32_t g, int exit, const std::array<double, 3>& w) {
  std::array<double, 3> next = {0, 0, 0};
  next[g % 3] = w[(exit + 2) % 3];            // Origin(g) = Dest(h)
  next[(g % 3 + 1) % 3] = w[(exit + 1) % 3];  // Dest(g) = Origin(h)
  return next;
}

// TracePath's step inside face *f from barycentric position *b: along the
// descent to the face's boundary, then across the edge it reaches into the
// next face (*f and *b move there), or onto a vertex (*at_vertex: the face's
// lowest vertex when the descent has no way forward, the edge's lower end at
// the boundary). Appends the point reached to *path, unless it crossed.
template <typename PointAt, typename VertexPoint>
void FaceStep(Tracer& tr, const MeshView& view, int32_t* f, std::array<double, 3>* b,
              int32_t* at_vertex, std::vector<PathPoint>* path, const PointAt& point_at,
              const VertexPoint& vertex_point) {
  double magnitude;
  const auto beta = tr.Descent(*f, *b, &magnitude);
  double t;
  const int exit = DescentExit(beta, *b, &t);
  if (exit < 0 || !(t > 1e-14) || !(magnitude > 0)) {
    *at_vertex = LowestVertex(tr, view, *f);
    path->push_back(vertex_point(*f, *at_vertex));
    return;
  }
  std::array<double, 3>& w = *b;
  for (int i = 0; i < 3; ++i) w[i] = std::max(w[i] + t * beta[i], 0.0);
  w[exit] = 0;
  const double sum = w[0] + w[1] + w[2];
  for (double& x : w) x /= sum;
  path->push_back(point_at(*f, w));
  for (int i = 0; i < 3; ++i) {
    if (w[i] >= 1 - 1e-12) *at_vertex = view.faces[3 * *f + i];
  }
  if (*at_vertex >= 0) {
    path->back() = vertex_point(*f, *at_vertex);
    return;
  }
  const int32_t h = 3 * *f + (exit + 1) % 3;  // the edge opposite `exit`
  const int32_t g = view.twins[h];
  if (g < 0) {
    const int32_t a = view.faces[3 * *f + (exit + 1) % 3], c = view.faces[3 * *f + (exit + 2) % 3];
    *at_vertex = tr.D(a) <= tr.D(c) ? a : c;
    path->push_back(vertex_point(*f, *at_vertex));
    return;
  }
  *f = g / 3;
  w = AcrossEdge(g, exit, w);
}

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

// True when every vertex `p` has weight on (weight > 1e-12) is a vertex of f.
bool FaceHolds(const MeshView& view, int32_t f, const SurfacePoint& p) {
  for (int i = 0; i < 3; ++i) {
    if (p.w[i] > 1e-12 && view.Corner(f, view.Vertex(p.face, i)) < 0) return false;
  }
  return true;
}

// A corridor from `from` to `to` found without the distance field: from
// face to face, each step heading for `to` along the chord projected into
// the face, until a face holds `to`. The crossings, with the ends, go to
// *path (consecutive points share a face, as StraightenPath needs). False
// when the walk reaches a vertex, the boundary or a dead end (the projected
// chord points back, past a ridge), crosses more than `max_steps` faces or
// walks more than twice the chord; then the caller traces instead.
bool WalkCorridor(const MeshView& view, const PathPoint& from, const PathPoint& to, int max_steps,
                  std::vector<PathPoint>* path) {
  path->assign({from});
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
      path->push_back(to);
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
  Vec3 x = from.position;
  // A walk that wanders (round a feature, or circling `to`) gives up early.
  const double max_length = 2 * (to.position - from.position).norm();
  double length = 0;
  for (int step = 0; step < max_steps && length <= max_length; ++step) {
    if (FaceHolds(view, f, to.point)) {
      path->push_back(to);
      return true;
    }
    const std::array<double, 3> beta = Velocity(view, f, to.position - x);
    double t;
    const int exit = DescentExit(beta, w, &t);
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
    path->push_back({SurfacePoint{f, w}, x});
    const int32_t g = view.twins[3 * f + (exit + 1) % 3];  // the edge opposite `exit`
    if (g < 0) return false;
    f = g / 3;
    w = AcrossEdge(g, exit, w);
  }
  return false;
}

}  // namespace

absl::StatusOr<std::vector<PathPoint>> QueryEngine::Path(const SurfacePoint& from,
                                                         const SurfacePoint& to) const {
  return Path(from, to, options_.exact_path_corridor);
}

absl::StatusOr<std::vector<PathPoint>> QueryEngine::Path(const SurfacePoint& from,
                                                         const SurfacePoint& to,
                                                         int32_t exact_corridor) const {
  GEODEX_ASSIGN_OR_RETURN(std::vector<PathPoint> path, ShortestTrace(from, to, TraceSearch::kFull));
  if (exact_corridor <= 0) return path;
  absl::StatusOr<std::vector<PathPoint>> exact = CorridorPath(path, exact_corridor);
  if (exact.ok() && PathLength(*exact) < PathLength(path)) {
    exact->front() = path.front();
    exact->back() = path.back();
    return *std::move(exact);
  }
  return path;
}

absl::StatusOr<std::vector<PathPoint>> QueryEngine::CorridorPath(const std::vector<PathPoint>& path,
                                                                 int32_t steps) const {
  // The corridor: the faces the path touches, grown across edges.
  std::vector<int32_t> faces;
  std::unordered_map<int32_t, int32_t> local_face;
  for (const PathPoint& p : path) {
    if (local_face.try_emplace(p.point.face, faces.size()).second) faces.push_back(p.point.face);
  }
  for (size_t begin = 0, step = 0; step < static_cast<size_t>(steps); ++step) {
    const size_t end = faces.size();
    for (size_t i = begin; i < end; ++i) {
      for (int k = 0; k < 3; ++k) {
        const int32_t twin = view_.twins[3 * faces[i] + k];
        if (twin < 0) continue;
        const int32_t g = twin / 3;
        if (local_face.try_emplace(g, faces.size()).second) faces.push_back(g);
      }
    }
    begin = end;
  }
  // A vertex whose corridor faces form more than one fan would make the
  // corridor non-manifold: such vertices get their whole star, until there
  // are none.
  const Tracer tr{*this, view_, {}, {}};
  for (bool pinched = true; pinched;) {
    pinched = false;
    std::unordered_map<int32_t, int32_t> a_face_of;  // corridor vertex -> a corridor face
    for (int32_t f : faces) {
      for (int k = 0; k < 3; ++k) a_face_of.try_emplace(view_.faces[3 * f + k], f);
    }
    for (const auto& [v, f] : a_face_of) {
      const std::vector<int32_t> star = tr.FacesAround(v, f);
      int fan_ends = 0;
      for (int32_t g : star) {
        if (!local_face.contains(g)) continue;
        const int32_t h = 3 * g + view_.Corner(g, v);  // the edge leaving v in g
        fan_ends += view_.twins[h] < 0 || !local_face.contains(view_.twins[h] / 3);
      }
      if (fan_ends <= 1) continue;
      pinched = true;
      for (int32_t g : star) {
        if (local_face.try_emplace(g, faces.size()).second) faces.push_back(g);
      }
    }
  }
  // As a mesh of its own, vertex order kept in every face.
  std::unordered_map<int32_t, int32_t> local_vertex;
  std::vector<mesh::Vec3> positions;
  std::vector<mesh::Triangle> triangles;
  for (int32_t f : faces) {
    mesh::Triangle t;
    for (int k = 0; k < 3; ++k) {
      const int32_t v = view_.faces[3 * f + k];
      auto [it, added] = local_vertex.try_emplace(v, positions.size());
      if (added) positions.push_back(view_.Position(v));
      t[k] = it->second;
    }
    triangles.push_back(t);
  }
  mesh::MeshOptions mesh_options;
  mesh_options.allow_zero_area_faces = true;  // as in the index's mesh
  GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh corridor,
                          mesh::Mesh::Create(std::move(positions), std::move(triangles),
                                             "path corridor", mesh_options));
  auto local = [&](const SurfacePoint& p) { return SurfacePoint{local_face.at(p.face), p.w}; };
  const SurfacePoint from = local(path.front().point), to = local(path.back().point);
  geodesic::ExactGeodesicSolver solver(corridor);
  geodesic::GeodesicOptions options;
  options.stop_points = {to};
  GEODEX_RETURN_IF_ERROR(solver.Propagate({from}, options));
  GEODEX_ASSIGN_OR_RETURN(const std::vector<SurfacePoint> back, solver.PathTo(to));
  std::vector<PathPoint> out;
  for (auto it = back.rbegin(); it != back.rend(); ++it) {
    const SurfacePoint p{faces[it->face], it->w};
    out.push_back({p, PositionOf(p)});
  }
  return out;
}

absl::StatusOr<std::vector<PathPoint>> QueryEngine::ShortestTrace(const SurfacePoint& from,
                                                                  const SurfacePoint& to,
                                                                  TraceSearch search) const {
  GEODEX_RETURN_IF_ERROR(Validate(from));
  GEODEX_RETURN_IF_ERROR(Validate(to));
  GEODEX_ASSIGN_OR_RETURN(std::vector<PathPoint> path, TracePath(from, to));
  if (!options_.straighten_paths) return path;
  path = StraightenPath(view_, std::move(path));
  double best = PathLength(path);
  // Keeps `candidate` (running from `from` to `to`) if it is shorter, with
  // the exact endpoints as given.
  auto offer = [&](std::vector<PathPoint> candidate) {
    const double length = PathLength(candidate);
    if (!(length < best)) return;
    candidate.front() = path.front();
    candidate.back() = path.back();
    path = std::move(candidate);
    best = length;
  };
  // A near pair's straightened trace that wraps round no vertex is a
  // straight line through the unfolded faces it crosses, a local geodesic;
  // between points this close, practically the shortest path. On scanned
  // and CAD meshes most near-pair traces are such, and close to exact, while
  // traces that wrapped were far off and needed the other trace (figures:
  // tests/bench/README.md).
  if (search == TraceSearch::kNearPair && !WrapsRoundAVertex(path)) return path;
  // The trace of the other point's field may run in a better corridor (the
  // two approximate fields err differently).
  absl::StatusOr<std::vector<PathPoint>> back = TracePath(to, from);
  if (back.ok()) {
    std::vector<PathPoint> other = StraightenPath(view_, *std::move(back));
    std::reverse(other.begin(), other.end());
    offer(std::move(other));
  }
  // Restarts. Beside a cut locus of the approximate field, the trace can
  // settle in a corridor round the wrong side of a feature: a local
  // geodesic, but longer than the shortest path, so the straightened
  // length exceeds the approximate distance by more than its usual error.
  // Then trace again from each vertex one ring out from either end's face,
  // join the end along one or two mesh edges, straighten, and keep the
  // shortest. Starts that close fall on both sides of the cut locus.
  if (search == TraceSearch::kNearPair ||
      !(best > kPathRestartRatio * DistanceUnchecked(from, to))) {
    return path;
  }
  for (int end = 0; end < 2; ++end) {
    const SurfacePoint& origin = end == 0 ? from : to;  // the traced field's source
    const SurfacePoint& tip = end == 0 ? to : from;
    for (const std::vector<PathPoint>& chain : RingChains(tip)) {
      // chain: a ring vertex, a vertex of tip's face, then tip itself.
      absl::StatusOr<std::vector<PathPoint>> trace = TracePath(origin, chain.front().point);
      if (!trace.ok()) continue;
      std::vector<PathPoint> candidate = *std::move(trace);
      candidate.insert(candidate.end(), chain.begin() + 1, chain.end());
      candidate = StraightenPath(view_, std::move(candidate));
      if (end == 1) std::reverse(candidate.begin(), candidate.end());
      offer(std::move(candidate));
    }
  }
  return path;
}

std::optional<QueryEngine::Trace> QueryEngine::PathNearDistance(const SurfacePoint& from,
                                                                const SurfacePoint& to,
                                                                double plausible) const {
  // First the corridors of the chord, from either end. A straightened walk
  // that wraps round no vertex is a straight line through the faces it
  // crosses, a local geodesic, as the straightened trace would be, found
  // without evaluating the distance field, so at a fraction of the trace's
  // cost. Walks that wrap are often in a wrong corridor, and so, rarely, is
  // a straight one longer than `plausible` (across a sharp feature); then
  // the trace decides. Every candidate is a surface path, so the shortest is
  // kept (figures: tests/bench/README.md).
  constexpr int kMaxWalkSteps = 256;
  const PathPoint ends[2] = {{from, PositionOf(from)}, {to, PositionOf(to)}};
  std::optional<double> doubted;
  std::vector<PathPoint> walk;
  for (int start = 0; start < (options_.walk_near_pairs ? 2 : 0); ++start) {
    if (!WalkCorridor(view_, ends[start], ends[1 - start], kMaxWalkSteps, &walk)) continue;
    std::optional<double> length = StraightLength(view_, walk);
    bool wraps = false;
    if (!length) {
      walk = StraightenPath(view_, std::move(walk));
      length = PathLength(walk);
      wraps = WrapsRoundAVertex(walk);
    }
    if (!wraps && *length <= plausible) return Trace{*length, false};
    doubted = std::min(*length, doubted.value_or(*length));
  }
  // Without Path's restarts, which double the cost of a near pair for a
  // small gain (tests/bench/README.md).
  const absl::StatusOr<std::vector<PathPoint>> path =
      ShortestTrace(from, to, TraceSearch::kNearPair);
  if (path.ok()) {
    const double length = PathLength(*path);
    if (!doubted || length <= *doubted) return Trace{length, WrapsRoundAVertex(*path)};
  }
  if (doubted) return Trace{*doubted, true};
  return std::nullopt;
}

std::vector<std::vector<PathPoint>> QueryEngine::RingChains(const SurfacePoint& p) const {
  auto vertex_point = [&](int32_t f, int32_t v) {
    SurfacePoint point{f, {0, 0, 0}};
    point.w[view_.Corner(f, v)] = 1;
    return PathPoint{point, view_.Position(v)};
  };
  const PathPoint tip{p, PositionOf(p)};
  Tracer tr{*this, view_, {}, {}};
  std::vector<std::vector<PathPoint>> chains;
  std::vector<int32_t> seen = {view_.faces[3 * p.face], view_.faces[3 * p.face + 1],
                               view_.faces[3 * p.face + 2]};
  for (int i = 0; i < 3; ++i) {
    const int32_t u = view_.faces[3 * p.face + i];
    for (int32_t g : tr.FacesAround(u, p.face)) {
      for (int k = 0; k < 3; ++k) {
        const int32_t w = view_.faces[3 * g + k];
        if (std::find(seen.begin(), seen.end(), w) != seen.end()) continue;
        seen.push_back(w);
        chains.push_back({vertex_point(g, w), vertex_point(g, u), tip});
      }
    }
  }
  return chains;
}

absl::StatusOr<std::vector<PathPoint>> QueryEngine::TracePath(const SurfacePoint& from_in,
                                                              const SurfacePoint& to_in) const {
  const SurfacePoint from = InLowestFaceIfVertex(Canonical(from_in)),
                     to = InLowestFaceIfVertex(Canonical(to_in));
  Tracer tr{*this, view_, Lift(from), {}};
  if (!(LiftedDistance(tr.source, Lift(to)) < std::numeric_limits<double>::infinity())) {
    return absl::NotFoundError("the two points lie on different connected components");
  }
  // The source's support: the vertices with non-zero weight.
  absl::InlinedVector<int32_t, 3> support;
  for (int i = 0; i < 3; ++i) {
    if (from.w[i] > 0) support.push_back(view_.faces[3 * from.face + i]);
  }
  auto contains_source = [&](int32_t f) {
    if (f == from.face) return true;
    for (int32_t v : support) {
      if (view_.Corner(f, v) < 0) return false;
    }
    return true;  // the source is a vertex or edge point of f
  };
  auto point_at = [&](int32_t f, const std::array<double, 3>& b) {
    const SurfacePoint p{f, b};
    return PathPoint{p, PositionOf(p)};
  };
  auto vertex_point = [&](int32_t f, int32_t v) {
    std::array<double, 3> b = {0, 0, 0};
    b[view_.Corner(f, v)] = 1;
    return point_at(f, b);
  };

  // Fallback when the descent stalls or circles: along mesh edges to the
  // source (FinishOnGraph).
  const PathPoint source = point_at(from.face, from.w);
  auto finish_on_graph = [&](std::vector<PathPoint>& path, int32_t v, int32_t f) {
    return FinishOnGraph(tr, view_, from, source, vertex_point, path, v, f);
  };

  std::vector<PathPoint> path;
  path.reserve(64);
  path.push_back(point_at(to.face, to.w));
  int32_t f = to.face;
  std::array<double, 3> b = to.w;
  int32_t at_vertex = -1;  // set while the path sits on a vertex
  for (int i = 0; i < 3; ++i) {
    if (b[i] >= 1) at_vertex = view_.faces[3 * f + i];
  }
  const int64_t max_steps = 8 * int64_t{index_->num_faces()} + 64;
  // A face entered again and again means the approximate field circles
  // (numerical flats, saddles of the interpolant): finish on the graph.
  absl::flat_hash_map<int32_t, int> visits;
  for (int64_t step = 0; step < max_steps; ++step) {
    if (++visits[f] > 6)
      return finish_on_graph(path, at_vertex >= 0 ? at_vertex : view_.faces[3 * f], f);
    if (contains_source(f)) {
      path.push_back(source);
      std::reverse(path.begin(), path.end());
      return path;
    }
    if (at_vertex >= 0) {
      // Leave the vertex into the face where the descent points inside.
      const int32_t v = at_vertex;
      const int32_t best_face = FaceToLeaveVertex(tr, view_, v, f, contains_source);
      if (best_face >= 0) {
        f = best_face;
        b = {0, 0, 0};
        b[view_.Corner(f, v)] = 1;
        if (contains_source(f)) continue;
        at_vertex = -1;
        // Fall through to the face step below from the vertex.
      } else {
        // Walk along the edge to the lowest neighbour, if lower.
        int32_t next, next_face;
        if (!LowerNeighbour(tr, view_, v, f, &next, &next_face)) {
          // A local minimum of the approximate field: finish along mesh
          // edges (A* towards the source), which always arrives.
          return finish_on_graph(path, v, f);
        }
        f = next_face;
        at_vertex = next;
        path.push_back(vertex_point(f, next));
        continue;
      }
    }
    FaceStep(tr, view_, &f, &b, &at_vertex, &path, point_at, vertex_point);
  }
  return finish_on_graph(path, at_vertex >= 0 ? at_vertex : view_.faces[3 * f], f);
}

}  // namespace geodex::query
