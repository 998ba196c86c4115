// The exponential map's work (the public call: core/query/exp_map.h).
//
// A vertex w is unfolded into the centre's tangent plane across each face
// (w, a, b) whose other corners already have coordinates, and the straight
// ray from the centre to the unfolded w tells where the geodesic crosses
// a-b; when it misses the edge, the geodesic bends round a (or b) and w
// takes that vertex's angle. Of the faces, the one giving the shortest path
// is used, as a propagation of distances would. On a developable surface the
// unfolding is exact.
//
// The map (ExpMapper) reads only the distances it is given, a
// SurfaceDistances: distances below kRefineScale * L from one exact
// propagation (exact_within), the others from the engine's Distance. It
// runs in the engine's ids. ExpMap, at the end, is the public call: it
// composes the map over the facade, which lends it the engine's distances
// (QueryEngine::WithDistances) and the input ids, and gives the answer in
// the input's.

#include "core/query/exp_map.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <queue>
#include <span>
#include <utility>

#include "absl/container/flat_hash_map.h"
#include "absl/container/inlined_vector.h"
#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/geometry/planar_unfolding.h"
#include "core/geometry/vec2.h"
#include "core/query/input_queries.h"
#include "core/query/engine/input_ids.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/query_engine.h"
#include "core/query/engine/surface_distances.h"

namespace geodex::query {
namespace {

using mesh::Vec3;

// A vertex placed round a neighbour is placed again when a path more than
// this share shorter appears. Well above rounding, well below the
// discretisation.
constexpr double kStale = 1e-9;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Placing a vertex again moves its neighbours when its angle moves by more
// than this (radians).
constexpr double kMoved = 1e-12;
// A guard: the placements converge as the paths shorten, but angles on a
// curved surface need not settle exactly.
constexpr int kMaxPlacements = 16;

using geometry::Cross;
using geometry::Vec2;
double Norm(const Vec2& a) { return std::hypot(a.x(), a.y()); }

// Into (-pi, pi].
double WrapAngle(double a) {
  a = std::remainder(a, 2 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2 * std::numbers::pi : a;
}

// What the map knows of one vertex.
struct Node {
  int32_t face = -1;  // a face holding the vertex
  double r = 0;       // distance from the centre
  double theta = 0;
  Vec2 at = Vec2::Zero();  // r (cos, sin) theta: the vertex in the centre's tangent plane
  // The length of the path theta was taken from: the unfolded ray, or the
  // way round a placed neighbour (longer than r when that was a stopgap).
  double path = 0;
  bool round_vertex = false;  // theta is a neighbour's: no unfolding reached w
  bool done = false;
  bool seed = false;  // placed directly (SeedFromFaces, SeedFromVertex): final
  int placements = 0;
};

// The state of one map: the vertices met so far and the queue of those
// whose distance is known but whose angle is not.
class ExpMapper {
 public:
  ExpMapper(const SurfaceDistances& surface, const mesh::SurfacePoint& centre,
            const ExpMapOptions& options)
      : surface_(surface), view_(surface.view), centre_(centre), options_(options) {}

  absl::StatusOr<std::vector<ExpMapVertex>> Run();

 private:
  // The centre's tangent frame: the plane of its face, e1 along the
  // reference direction.
  absl::Status MakeFrame();
  // The vertices whose geodesic from the centre is a straight segment in
  // one face (those of the faces holding the centre), placed directly.
  void SeedFromFaces();
  void SeedFromVertex(int32_t v);
  // Records a vertex placed at `at` in the tangent plane.
  void Seed(int32_t v, int32_t face, const Vec2& at);
  // The angle of a vertex from its placed neighbours (the header comment),
  // and the length of the path it comes from.
  struct Angle {
    double theta = 0;
    double path = std::numeric_limits<double>::infinity();
    bool round_vertex = false;
  };
  Angle AngleOf(int32_t w, const Node& node) const;
  // Places w at `angle`; then, as long as placing a vertex gives a placed
  // neighbour a shorter path than the one its angle came from, that
  // neighbour is placed again (see Run).
  void Place(int32_t w, Angle angle);
  // Meets the vertices round a placed vertex (their distances are queried
  // and they join the queue) when the disc may reach past it.
  absl::Status Expand(int32_t v);

  Vec2 InFrame(const Vec3& x) const {
    const Vec3 d = x - origin_;
    return Vec2(d.dot(e1_), d.dot(e2_));
  }
  double Edge(int32_t a, int32_t b) const { return (view_.Position(a) - view_.Position(b)).norm(); }

  const SurfaceDistances& surface_;
  const MeshView view_;
  mesh::SurfacePoint centre_;
  const ExpMapOptions& options_;
  // Exact distances of the vertices within exact_radius_ of the centre
  // (SurfaceDistances::exact_within), when the distance options refine.
  absl::flat_hash_map<int32_t, double> exact_;
  double exact_radius_ = -1;
  Vec3 origin_, normal_, e1_, e2_;
  absl::flat_hash_map<int32_t, Node> nodes_;
  using Entry = std::pair<double, int32_t>;  // (r, vertex)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue_;
};

absl::Status ExpMapper::MakeFrame() {
  const int32_t* f = &view_.faces[3 * centre_.face];
  const Vec3 p0 = view_.Position(f[0]), p1 = view_.Position(f[1]), p2 = view_.Position(f[2]);
  origin_ = centre_.w[0] * p0 + centre_.w[1] * p1 + centre_.w[2] * p2;
  normal_ = (p1 - p0).cross(p2 - p0);
  if (!(normal_.norm() > 0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the centre's face %d is degenerate (no tangent plane)", centre_.face));
  }
  normal_.normalize();
  Vec3 e1 = p1 - p0;
  if (options_.reference_direction) {
    e1 = *options_.reference_direction;
    if (!e1.allFinite()) {
      return absl::InvalidArgumentError("the reference direction is not finite");
    }
  }
  const double length = e1.norm();
  e1 -= e1.dot(normal_) * normal_;
  if (!(e1.norm() > 1e-9 * length)) {
    return absl::InvalidArgumentError(
        "the reference direction is zero or perpendicular to the centre's face");
  }
  e1_ = e1.normalized();
  e2_ = normal_.cross(e1_);
  return absl::OkStatus();
}

void ExpMapper::Seed(int32_t v, int32_t face, const Vec2& at) {
  Node& node = nodes_[v];
  node.face = face;
  node.r = Norm(at);
  node.theta = node.r > 0 ? std::atan2(at.y(), at.x()) : 0;
  node.at = at;
  node.path = node.r;
  node.done = true;
  node.seed = true;
}

void ExpMapper::SeedFromFaces() {
  // The centre's face, and across an edge the centre lies on, the face
  // beyond: the hinge is flat, so that face unfolds about the shared edge.
  const int32_t f = centre_.face;
  for (int i = 0; i < 3; ++i)
    Seed(view_.Vertex(f, i), f, InFrame(view_.Position(view_.Vertex(f, i))));
  for (int i = 0; i < 3; ++i) {
    if (centre_.w[i] > 0) continue;
    const int32_t h = 3 * f + (i + 1) % 3;  // the edge opposite corner i
    const int32_t g = view_.twins[h];
    if (g < 0) continue;
    const int32_t a = view_.Vertex(f, (i + 1) % 3), b = view_.Vertex(f, (i + 2) % 3);
    const int32_t y = view_.faces[3 * (g / 3) + (g % 3 + 2) % 3];  // opposite the shared edge
    // (b, a, y) is counter-clockwise in g, so y lies left of b -> a.
    const Vec2 ua = nodes_[a].at, ub = nodes_[b].at;
    const double l = Norm(ua - ub);
    double x, hgt;
    geometry::Place(l, Edge(b, y), Edge(a, y), &x, &hgt);
    const Vec2 along = (1 / l) * (ua - ub), left(-along.y(), along.x());
    Seed(y, g / 3, ub + x * along + hgt * left);
  }
}

void ExpMapper::SeedFromVertex(int32_t v) {
  // The faces round v in counter-clockwise order (direction 1 of
  // MeshView::Turn), from the boundary when there is one.
  int32_t start = centre_.face;
  bool closed = false;
  for (int step = 0; step < MeshView::kMaxFanSteps; ++step) {
    const int32_t g = view_.Turn(start, v, 0);
    if (g < 0) break;
    if (g == centre_.face) {
      closed = true;
      break;
    }
    start = g;
  }
  if (closed) start = centre_.face;
  struct Wedge {
    int32_t face, a, b;  // (v, a, b) counter-clockwise
    double from, angle;  // where the wedge starts and its angle at v
  };
  std::vector<Wedge> fan;
  double total = 0;
  for (int32_t g = start, step = 0; g >= 0 && step < MeshView::kMaxFanSteps; ++step) {
    const int k = view_.Corner(g, v);
    const int32_t a = view_.Vertex(g, (k + 1) % 3), b = view_.Vertex(g, (k + 2) % 3);
    const Vec3 pv = view_.Position(v);
    const Vec3 da = view_.Position(a) - pv, db = view_.Position(b) - pv;
    const double angle = std::atan2(da.cross(db).norm(), da.dot(db));
    fan.push_back({g, a, b, total, angle});
    total += angle;
    g = view_.Turn(g, v, 1);
    if (g == start) break;
  }
  // A cone point (an interior vertex whose angles do not sum to a full
  // turn) has its angles scaled to one; a boundary vertex keeps its wedge.
  const double scale = closed && total > 0 ? 2 * std::numbers::pi / total : 1;
  // The reference direction's angle within the centre's face, from its
  // edge v -> a.
  double reference = 0;
  for (const Wedge& w : fan) {
    if (w.face != centre_.face) continue;
    const Vec3 ea = (view_.Position(w.a) - view_.Position(v)).normalized();
    reference = w.from + std::atan2(e1_.dot(normal_.cross(ea)), e1_.dot(ea));
  }
  Seed(v, centre_.face, Vec2::Zero());
  for (const Wedge& w : fan) {
    for (const auto& [u, angle] : {std::pair{w.a, w.from}, std::pair{w.b, w.from + w.angle}}) {
      const double theta = WrapAngle(scale * (angle - reference));
      const double r = Edge(v, u);
      Seed(u, w.face, Vec2(r * std::cos(theta), r * std::sin(theta)));
    }
  }
}

ExpMapper::Angle ExpMapper::AngleOf(int32_t w, const Node& node) const {
  Angle best;
  auto consider = [&](double length, double theta, bool round_vertex) {
    if (length < best.path) best = {theta, length, round_vertex};
  };
  absl::InlinedVector<int32_t, 16> star;
  view_.FacesAround(w, node.face, &star);
  for (const int32_t g : star) {
    const int k = view_.Corner(g, w);
    const int32_t a = view_.Vertex(g, (k + 1) % 3), b = view_.Vertex(g, (k + 2) % 3);
    const auto ia = nodes_.find(a), ib = nodes_.find(b);
    const bool a_done = ia != nodes_.end() && ia->second.done;
    const bool b_done = ib != nodes_.end() && ib->second.done;
    // Through a placed corner: the geodesic bends round it.
    if (a_done) consider(ia->second.r + Edge(w, a), ia->second.theta, true);
    if (b_done) consider(ib->second.r + Edge(w, b), ib->second.theta, true);
    if (!a_done || !b_done) continue;
    // Across the edge a-b, unfolded into a plane with a at the origin and b
    // on the x axis: w above it ((w, a, b) is counter-clockwise), and below
    // it the virtual source, the point at distances r_a, r_b from a and b.
    // When the straight line from the source to w crosses the edge, the
    // geodesic does, and w's angle divides a's and b's as the line divides
    // the angle the edge subtends at the source: exact on a developable
    // surface, and on a curved one it keeps the angles a and b already have
    // (their difference is not the planar one there).
    // The centre must lie on the other side of a-b from w (the placed a and
    // b say which side it is on); otherwise the geodesic to w does not
    // cross this edge.
    if (!(Cross(ia->second.at, ib->second.at) < 0)) continue;
    const double l = Edge(a, b);
    double wx, wy, sx, sy;
    geometry::Place(l, Edge(w, a), Edge(w, b), &wx, &wy);
    geometry::Place(l, ia->second.r, ib->second.r, &sx, &sy);
    const Vec2 to_a(-sx, sy), to_b(l - sx, sy), to_w(wx - sx, wy + sy);
    const double span = std::atan2(Cross(to_a, to_b), to_a.x() * to_b.x() + to_a.y() * to_b.y());
    const double part = std::atan2(Cross(to_a, to_w), to_a.x() * to_w.x() + to_a.y() * to_w.y());
    if (!(std::abs(span) > 0)) continue;
    const double share = part / span;
    if (!(share >= 0 && share <= 1)) continue;
    const double turn = std::remainder(ib->second.theta - ia->second.theta, 2 * std::numbers::pi);
    consider(Norm(to_w), ia->second.theta + share * turn, false);
  }
  return best;
}

void ExpMapper::Place(int32_t w, Angle angle) {
  struct Work {
    int32_t vertex;
    Angle angle;
  };
  std::vector<Work> work = {{w, angle}};
  while (!work.empty()) {
    const Work item = work.back();
    work.pop_back();
    Node& node = nodes_.at(item.vertex);
    const bool again = node.done;
    node.theta = item.angle.theta;
    node.path = item.angle.path;
    node.round_vertex = item.angle.round_vertex;
    node.at = {node.r * std::cos(node.theta), node.r * std::sin(node.theta)};
    node.done = true;
    ++node.placements;
    // A vertex placed before one of its neighbours had only its other
    // neighbours to go by: in an obtuse triangle the edge the geodesic
    // crosses can have an end farther from the centre than the vertex
    // itself. Placing x gives such a neighbour a shorter path, and placing
    // x again moves the neighbours placed from it: both are placed again.
    absl::InlinedVector<int32_t, 16> star;
    view_.FacesAround(item.vertex, node.face, &star);
    for (const int32_t g : star) {
      for (int i = 0; i < 3; ++i) {
        const int32_t y = view_.Vertex(g, i);
        if (y == item.vertex) continue;
        const auto it = nodes_.find(y);
        if (it == nodes_.end() || !it->second.done || it->second.seed ||
            it->second.placements >= kMaxPlacements) {
          continue;
        }
        const Node& other = it->second;
        if (!again && !other.round_vertex) continue;
        const Angle better = AngleOf(y, other);
        const bool shorter = better.path < other.path * (1 - kStale);
        const bool moved =
            std::abs(std::remainder(better.theta - other.theta, 2 * std::numbers::pi)) > kMoved;
        if (shorter || (again && moved)) work.push_back({y, better});
      }
    }
  }
}

absl::Status ExpMapper::Expand(int32_t v) {
  const Node& node = nodes_.at(v);
  absl::InlinedVector<int32_t, 16> star;
  view_.FacesAround(v, node.face, &star);
  double longest = 0;
  for (const int32_t g : star) {
    for (int i = 0; i < 3; ++i) longest = std::max(longest, Edge(v, view_.Vertex(g, i)));
  }
  // A geodesic to a vertex inside the radius crosses edges at points inside
  // it, and each such edge has an end within radius + its length: those
  // ends are expanded, so no vertex inside the radius is missed.
  if (node.r > options_.radius + longest) return absl::OkStatus();
  for (const int32_t g : star) {
    for (int i = 0; i < 3; ++i) {
      const int32_t u = view_.Vertex(g, i);
      if (nodes_.contains(u)) continue;
      const auto known = exact_.find(u);
      double r = known != exact_.end() ? known->second : kInfinity;
      if (!(r <= exact_radius_)) {
        mesh::SurfacePoint p{g, {0, 0, 0}};
        p.w[i] = 1;
        GEODEX_ASSIGN_OR_RETURN(r, surface_.distance(centre_, p));
      }
      Node& met = nodes_[u];
      met.face = g;
      met.r = r;
      if (std::isfinite(r)) queue_.push({r, u});
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<ExpMapVertex>> ExpMapper::Run() {
  if (!(std::isfinite(options_.radius) && options_.radius > 0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the radius must be finite and > 0, got %g", options_.radius));
  }
  double sum = 0;
  for (double& w : centre_.w) sum += (w = std::max(w, 0.0));
  for (double& w : centre_.w) w /= sum;
  GEODEX_RETURN_IF_ERROR(MakeFrame());

  int32_t at_vertex = -1;
  for (int i = 0; i < 3; ++i) {
    if (centre_.w[i] >= 1 - 1e-12) at_vertex = view_.Vertex(centre_.face, i);
  }
  // Near the centre, where the O(1) distance errs most relative to r and the
  // engine would refine vertex after vertex by traces, one local exact
  // propagation gives every r at once, exactly.
  if (options_.distance.near_pairs != NearPairs::kUnfold) {
    exact_radius_ = std::min(options_.radius, kRefineScale * surface_.scale_length);
    GEODEX_ASSIGN_OR_RETURN(const RadiusField within, surface_.exact_within(centre_, exact_radius_));
    exact_.reserve(within.vertices.size());
    for (size_t i = 0; i < within.vertices.size(); ++i) {
      exact_.emplace(within.vertices[i], within.distance[i]);
    }
  }
  if (at_vertex >= 0) {
    SeedFromVertex(at_vertex);
  } else {
    SeedFromFaces();
  }
  std::vector<int32_t> seeds;
  for (const auto& [v, node] : nodes_) seeds.push_back(v);
  std::sort(seeds.begin(), seeds.end());  // a deterministic order of expansion
  for (const int32_t v : seeds) GEODEX_RETURN_IF_ERROR(Expand(v));

  while (!queue_.empty()) {
    const int32_t w = queue_.top().second;
    queue_.pop();
    Node& node = nodes_.at(w);
    if (node.done) continue;
    Place(w, AngleOf(w, node));
    GEODEX_RETURN_IF_ERROR(Expand(w));
  }

  std::vector<ExpMapVertex> out;
  for (const auto& [v, node] : nodes_) {
    if (!node.done || !(node.r <= options_.radius)) continue;
    out.push_back({v, node.r, WrapAngle(node.theta), node.at.x(), node.at.y()});
  }
  std::sort(out.begin(), out.end(),
            [](const ExpMapVertex& a, const ExpMapVertex& b) { return a.vertex < b.vertex; });
  return out;
}

}  // namespace

absl::StatusOr<std::vector<ExpMapVertex>> ExpMap(const InputQueries& queries,
                                                 const EnginePoints& centres, size_t i,
                                                 ExpMapOptions options, QueryScratch* scratch) {
  const SurfacePoint& internal = centres.engine_point(i);
  const int32_t input_face = centres.input_face(i);
  const InputIds& ids = queries.ids();
  // A re-oriented face's normal is the input face's reversed, and its first
  // edge another edge: give the input's first edge, and mirror θ. A piece of
  // a split face has other edges too.
  const bool mirrored = ids.Reoriented(input_face);
  if ((mirrored || ids.split()) && !options.reference_direction.has_value()) {
    const mesh::Triangle t = ids.InputFace(input_face);
    const std::span<const double> p = queries.index().positions();
    options.reference_direction = mesh::Vec3(p[3 * t[1]], p[3 * t[1] + 1], p[3 * t[1] + 2]) -
                                  mesh::Vec3(p[3 * t[0]], p[3 * t[0] + 1], p[3 * t[0] + 2]);
  }
  GEODEX_ASSIGN_OR_RETURN(
      std::vector<ExpMapVertex> map,
      queries.engine().WithDistances(
          options.distance, scratch, [&](const SurfaceDistances& surface) {
            return ExpMapper(surface, internal, options).Run();
          }));
  if (ids.identity()) return map;
  // Midpoints of the long-edge split are no input vertices.
  std::erase_if(map,
                [&](const ExpMapVertex& e) { return ids.InputVertex(e.vertex) == mesh::kNone; });
  for (ExpMapVertex& e : map) {
    e.vertex = ids.InputVertex(e.vertex);
    if (mirrored) {
      e.theta = e.theta == 0 || e.theta == std::numbers::pi ? e.theta : -e.theta;
      e.v = -e.v;
    }
  }
  // One entry per input vertex: the copy of smallest r.
  std::stable_sort(map.begin(), map.end(), [](const ExpMapVertex& a, const ExpMapVertex& b) {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.r < b.r;
  });
  map.erase(std::unique(
                map.begin(), map.end(),
                [](const ExpMapVertex& a, const ExpMapVertex& b) { return a.vertex == b.vertex; }),
            map.end());
  return map;
}

}  // namespace geodex::query
