#include "core/query/engine/internal/paths/gradient_path.h"

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
#include "core/geometry/planar_unfolding.h"
#include "core/query/engine/internal/paths/path_straightening.h"

namespace geodex::query {
namespace {

using mesh::Vec3;

// The direction in which the field whose values at face f's corners are
// d leaves the point at barycentric position b: towards the source those
// distances place in the face's plane (trilateration), exact where the
// field is planar; where they fit no point, down the gradient of their
// linear interpolant.
Vec3 TowardsSource(const MeshView& mesh, int32_t f, const std::array<double, 3>& d,
                   const std::array<double, 3>& b) {
  const Vec3 v[3] = {mesh.Position(mesh.Vertex(f, 0)), mesh.Position(mesh.Vertex(f, 1)),
                     mesh.Position(mesh.Vertex(f, 2))};
  const Vec3 e1 = v[1] - v[0], e2 = v[2] - v[0];
  const Vec3 n = e1.cross(e2);
  const double l = e1.norm();
  const Vec3 ux = e1 / l;
  const Vec3 uy = n.cross(e1).normalized();
  const double cx = e2.dot(ux), cy = e2.dot(uy);
  if (cy > 1e-6 * l) {
    double sx, sy;
    geometry::Trilaterate(l, cx, cy, d[0], d[1], d[2], &sx, &sy);
    const double r0 = std::sqrt(sx * sx + sy * sy);
    if (std::abs(r0 - d[0]) < 1e-3 * (d[0] + l)) {
      return v[0] + sx * ux + sy * uy - (b[0] * v[0] + b[1] * v[1] + b[2] * v[2]);
    }
  }
  const double area2 = n.squaredNorm();
  Vec3 dir = Vec3::Zero();
  for (int i = 0; i < 3; ++i) dir -= d[i] * n.cross(v[(i + 2) % 3] - v[(i + 1) % 3]) / area2;
  return dir;
}

struct Tracer {
  const Lifting& lifting;
  const LiftedUnfolding& unfolding;
  const MeshView& mesh;
  LiftedPoint source;
  absl::flat_hash_map<int32_t, double> cache;

  // Approximate distance from the source to vertex v (O(1), memoised).
  double D(int32_t v) {
    auto [it, inserted] = cache.try_emplace(v, 0.0);
    if (inserted) it->second = unfolding.Distance(source, lifting.VertexLift(v));
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
    const Vec3 n = (v[1] - v[0]).cross(v[2] - v[0]);
    const double area2 = n.squaredNorm();
    Vec3 grad_b[3];
    for (int i = 0; i < 3; ++i) grad_b[i] = n.cross(v[(i + 2) % 3] - v[(i + 1) % 3]) / area2;
    const Vec3 dir = DescentDirection(f, b);
    *magnitude = dir.norm();
    return {grad_b[0].dot(dir), grad_b[1].dot(dir), grad_b[2].dot(dir)};
  }

  // Descent's direction, in space: towards the source unfolded into the
  // face's plane.
  Vec3 DescentDirection(int32_t f, const std::array<double, 3>& b) {
    return TowardsSource(mesh, f,
                         {D(mesh.Vertex(f, 0)), D(mesh.Vertex(f, 1)), D(mesh.Vertex(f, 2))}, b);
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
// (figures: tests/bench/throughput.md).
constexpr double kPathRestartRatio = 1.01;

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

// The vertex of face f with the lowest approximate distance (first on ties).
int32_t LowestVertex(Tracer& tr, const MeshView& view, int32_t f) {
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (tr.D(view.faces[3 * f + i]) < tr.D(view.faces[3 * f + k])) k = i;
  }
  return view.faces[3 * f + k];
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

}  // namespace

Vec3 GradientPaths::Heading(const SurfacePoint& from, const SurfacePoint& to) const {
  // Three answers, no Tracer: its memo would allocate for each pair.
  const LiftedPoint source = lifting_.Lift(to);
  std::array<double, 3> d;
  for (int i = 0; i < 3; ++i) {
    d[i] = unfolding_.Distance(source, lifting_.VertexLift(view_.Vertex(from.face, i)));
  }
  return TowardsSource(view_, from.face, d, from.w);
}

absl::StatusOr<std::vector<PathPoint>> GradientPaths::Shortest(const SurfacePoint& from,
                                                               const SurfacePoint& to,
                                                               Search search) const {
  GEODEX_ASSIGN_OR_RETURN(std::vector<PathPoint> path, Trace(from, to));
  if (!straighten_) return path;
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
  // tests/bench/throughput.md).
  if (search == Search::kNearPair && !WrapsRoundAVertex(path)) return path;
  // The trace of the other point's field may run in a better corridor (the
  // two approximate fields err differently).
  absl::StatusOr<std::vector<PathPoint>> back = Trace(to, from);
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
  if (search == Search::kNearPair ||
      !(best > kPathRestartRatio * O1Distance(view_, lifting_, unfolding_, from, to))) {
    return path;
  }
  for (int end = 0; end < 2; ++end) {
    const SurfacePoint& origin = end == 0 ? from : to;  // the traced field's source
    const SurfacePoint& tip = end == 0 ? to : from;
    for (const std::vector<PathPoint>& chain : RingChains(tip)) {
      // chain: a ring vertex, a vertex of tip's face, then tip itself.
      absl::StatusOr<std::vector<PathPoint>> trace = Trace(origin, chain.front().point);
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

std::vector<std::vector<PathPoint>> GradientPaths::RingChains(const SurfacePoint& p) const {
  auto vertex_point = [&](int32_t f, int32_t v) {
    SurfacePoint point{f, {0, 0, 0}};
    point.w[view_.Corner(f, v)] = 1;
    return PathPoint{point, view_.Position(v)};
  };
  const PathPoint tip{p, view_.PositionOf(p)};
  Tracer tr{lifting_, unfolding_, view_, {}, {}};
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

absl::StatusOr<std::vector<PathPoint>> GradientPaths::Trace(const SurfacePoint& from_in,
                                                            const SurfacePoint& to_in) const {
  const SurfacePoint from = view_.InLowestFaceIfVertex(view_.Canonical(from_in)),
                     to = view_.InLowestFaceIfVertex(view_.Canonical(to_in));
  Tracer tr{lifting_, unfolding_, view_, lifting_.Lift(from), {}};
  if (!(unfolding_.Distance(tr.source, lifting_.Lift(to)) <
        std::numeric_limits<double>::infinity())) {
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
    return PathPoint{p, view_.PositionOf(p)};
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
  const int64_t max_steps = 8 * static_cast<int64_t>(view_.faces.size() / 3) + 64;
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
