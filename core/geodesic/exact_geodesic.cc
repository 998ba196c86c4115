#include "core/geodesic/exact_geodesic.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::geodesic {
namespace {

using mesh::kNone;
using mesh::Vec3;

// Vertices whose angle sum reaches 2*pi minus this are treated as saddles
// (pseudo-sources): it keeps flat vertices exact despite rounding.
constexpr double kSaddleSlack = 1e-9;

// The sources on the mesh and inside the face region, if there is one, and
// the initial distances one per vertex.
absl::Status CheckSources(const Mesh& mesh, std::span<const SurfacePoint> sources,
                          const GeodesicOptions& options) {
  for (const SurfacePoint& s : sources) {
    GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(mesh, s));
  }
  GEODEX_RETURN_IF_ERROR(CheckInitialDistances(options.initial_distance, mesh.num_vertices()));
  if (options.face_region.empty()) return absl::OkStatus();
  if (options.face_region.size() != static_cast<size_t>(mesh.num_faces())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("face_region has %d entries, the mesh %d faces", options.face_region.size(),
                        mesh.num_faces()));
  }
  for (const SurfacePoint& s : sources) {
    if (options.face_region[s.face] == 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("a source lies in face %d, outside the face region", s.face));
    }
  }
  return absl::OkStatus();
}

// The stop points on the mesh, the stop vertices its vertices.
absl::Status CheckStops(const Mesh& mesh, const GeodesicOptions& options) {
  for (const SurfacePoint& p : options.stop_points) {
    GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(mesh, p));
  }
  for (int32_t v : options.stop_vertices) {
    if (v < 0 || v >= mesh.num_vertices()) {
      return absl::OutOfRangeError(absl::StrFormat("stop vertex %d out of range", v));
    }
  }
  return absl::OkStatus();
}

}  // namespace

ExactGeodesicSolver::ExactGeodesicSolver(const Mesh& mesh)
    : mesh_(mesh), frame_(HalfEdgeFrames(mesh)) {
  const int32_t nh = mesh.num_halfedges();
  corner_angle_.resize(nh);
  for (int32_t h = 0; h < nh; ++h) corner_angle_[h] = std::atan2(frame_[h].cy, frame_[h].cx);
  emits_.resize(mesh.num_vertices());
  pinched_.resize(mesh.num_vertices());
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    pinched_[v] = mesh::TouchesZeroLengthEdge(mesh, v);
    emits_[v] = mesh.IsReferenced(v) && (mesh.IsBoundaryVertex(v) || pinched_[v] ||
                                         mesh.AngleSum(v) >= 2 * std::numbers::pi - kSaddleSlack);
  }
}

void ExactGeodesicSolver::Reset() {
  // Clearing only what the last propagation touched keeps a propagation that
  // reaches a few hundred faces of a large mesh from paying O(n) for it.
  if (full_reset_) {
    dist_.assign(mesh_.num_vertices(), kInfinity);
    nearest_.assign(mesh_.num_vertices(), kNone);
    origin_.assign(mesh_.num_vertices(), VertexOrigin{});
    region_border_.assign(mesh_.num_vertices(), 0);
    edge_head_.assign(mesh_.num_halfedges(), kNone);
    split_.assign(mesh_.num_halfedges(), Split{});
    full_reset_ = false;
  } else {
    for (const int32_t v : touched_vertices_) {
      dist_[v] = kInfinity;
      nearest_[v] = kNone;
      origin_[v] = VertexOrigin{};
      region_border_[v] = 0;
    }
    for (const int32_t h : touched_halfedges_) {
      edge_head_[h] = kNone;
      split_[h] = Split{};
    }
  }
  touched_vertices_.clear();
  touched_halfedges_.clear();
  region_ = {};
  border_windows_.clear();
  settled_below_ = kInfinity;
  windows_.clear();
  queue_.Clear();
  face_sources_.clear();
  sources_.clear();
  stats_ = {};
}

absl::Status ExactGeodesicSolver::Propagate(std::span<const SurfacePoint> sources,
                                            const GeodesicOptions& options) {
  Reset();
  if (sources.empty()) return absl::InvalidArgumentError("no sources given");
  GEODEX_RETURN_IF_ERROR(CheckSources(mesh_, sources, options));
  if (!options.initial_distance.empty()) {
    // dist_ becomes finite where no propagation touches it.
    full_reset_ = true;
    for (int32_t v = 0; v < mesh_.num_vertices(); ++v) {
      const double d = options.initial_distance[v];
      if (d < kInfinity) {
        dist_[v] = d;
        origin_[v] = {Via::kInitial, kNone};
      }
    }
  }
  GEODEX_RETURN_IF_ERROR(CheckStops(mesh_, options));
  region_ = options.face_region;
  stop_radius_ = options.stop_radius;
  // With slack for rounding: where the way on to the point is straight (a
  // flat surface, a saddle seen straight from it), the straight-line bound
  // equals the distance, and rounding must not prune that way.
  prune_length_ = options.prune_length * (1 + 1e-9);
  prune_point_ = options.prune_point;
  stop_vertices_ = options.stop_vertices;
  stop_points_ = options.stop_points;
  max_windows_ = options.max_windows > 0 ? options.max_windows
                                         : 400 * int64_t{mesh_.num_halfedges()} + 1'000'000;
  max_vertices_ = options.max_vertices;

  sources_.assign(sources.begin(), sources.end());
  for (int32_t s = 0; s < static_cast<int32_t>(sources.size()); ++s) {
    GEODEX_RETURN_IF_ERROR(AddSource(sources[s], s));
  }

  const bool has_targets = !stop_vertices_.empty() || !stop_points_.empty();
  int64_t pops = 0;
  while (!queue_.empty()) {
    const auto [key, id] = queue_.Pop([this](int32_t soon) {
      // PropagateWindow's first read of a window is otherwise a cache miss
      // that costs about as much as the rest of it.
      if (soon >= 0) __builtin_prefetch(&windows_[soon]);
    });
    // Everything still queued is at least `key` away (up to rounding): past
    // the stop radius, or once the targets are no farther, nothing is left
    // to improve.
    if (key > stop_radius_ || (has_targets && (++pops & 63) == 0 && TargetsSettled(key))) {
      settled_below_ = key;
      break;
    }
    if (id < 0) {
      const int32_t v = ~id;
      if (key != dist_[v]) continue;  // superseded by a shorter path
      ++stats_.vertex_events;
      EmitFromVertex(v);
    } else {
      // Windows were filtered when created; re-checking here discards almost
      // none (measured: < 0.1%) and costs a quarter of the time.
      ++stats_.windows_propagated;
      PropagateWindow(id);
    }
    if (static_cast<int64_t>(windows_.size()) > max_windows_) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "geodesic propagation on %s exceeded %d windows", mesh_.name(), max_windows_));
    }
    if (max_vertices_ > 0 && static_cast<int64_t>(touched_vertices_.size()) > max_vertices_) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "geodesic propagation on %s reached more than %d vertices", mesh_.name(), max_vertices_));
    }
  }
  queue_.Clear();
  region_ = {};
  return absl::OkStatus();
}

uint8_t ExactGeodesicSolver::RegionBorderState(int32_t v) {
  if (region_.empty()) return kInsideRegion;
  uint8_t& state = region_border_[v];
  if (state != kUnknown) return state;
  // The region's faces round v: their angle, and how many separate fans they
  // make.
  const auto fan = mesh_.Outgoing(v);
  const bool closed = !mesh_.IsBoundaryVertex(v);
  double angle = 0;
  int pieces = 0;
  bool all = true;
  for (size_t k = 0; k < fan.size(); ++k) {
    const bool in = region_[Mesh::FaceOf(fan[k])] != 0;
    all = all && in;
    if (!in) continue;
    angle += corner_angle_[fan[k]];
    const bool previous_in = k > 0 ? region_[Mesh::FaceOf(fan[k - 1])] != 0
                                   : closed && region_[Mesh::FaceOf(fan.back())] != 0;
    pieces += !previous_in;
  }
  // A shortest path inside the region bends round v only where the region's
  // angle there exceeds pi (a path through a corner of less is shortened by
  // cutting it) or where it passes from one of its fans to another.
  if (all) {
    state = kInsideRegion;
  } else if (pieces > 1 || angle > std::numbers::pi - kSaddleSlack) {
    state = kReflexBorder;
  } else {
    state = kConvexBorder;
  }
  return state;
}

absl::Status ExactGeodesicSolver::AddSource(const SurfacePoint& p, int32_t source) {
  const SourcePlace place = ClassifySource(mesh_, p);
  if (place.kind == SourcePlace::kVertex) {
    const int32_t v = place.vertex;
    if (dist_[v] > 0 || origin_[v].via == Via::kInitial) {
      Touch(v);
      dist_[v] = 0;
      nearest_[v] = source;
      origin_[v] = {Via::kSource, source};
      EmitFromVertex(v);
    }
    return absl::OkStatus();
  }
  if (place.kind == SourcePlace::kFace) {
    AddFaceSource(p.face, place.w, source, kNone);
    return absl::OkStatus();
  }
  // On an edge: both faces hold the source.
  const int32_t h = place.halfedge;
  AddFaceSource(p.face, place.w, source, h);
  const int32_t g = mesh_.Twin(h);
  if (g != kNone && InRegion(Mesh::FaceOf(g)))
    AddFaceSource(Mesh::FaceOf(g), WeightsInTwin(h, g, place.w), source, g);
  return absl::OkStatus();
}

void ExactGeodesicSolver::AddFaceSource(int32_t face, const std::array<double, 3>& w,
                                        int32_t source, int32_t skip_halfedge) {
  const SurfacePoint p{face, w};
  const Vec3 x = mesh::PositionOf(mesh_, p);
  face_sources_.push_back({face, source, x});
  for (int i = 0; i < 3; ++i) {
    const int32_t v = mesh_.face(face)[i];
    UpdateVertex(v, (mesh_.position(v) - x).norm(), source, Via::kSource, source);
  }
  for (int i = 0; i < 3; ++i) {
    const int32_t h = 3 * face + i;
    const int32_t t = mesh_.Twin(h);
    if (h == skip_halfedge || t == kNone) continue;
    const auto [px, py] = InFrame(h, p);
    const double l = frame_[h].length;
    Window win{};
    win.b0 = 0;
    win.b1 = l;
    win.sx = l - px;  // mirror into the twin's frame
    win.sy = -py;
    win.sigma = 0;
    win.h = t;
    win.parent = kNone;
    win.pseudo = kNone;
    win.source = source;
    PushWindow(win);
  }
}

double ExactGeodesicSolver::BackAngle(int32_t v) const {
  // Angles around v are measured counter-clockwise from the first outgoing
  // half-edge; corner k spans [phi_k, phi_k + angle of corner k].
  // At a pinch (an edge of length 0) the corner angles say nothing of the
  // directions: emit everywhere.
  if (pinched_[v]) return -1;
  const VertexOrigin& o = origin_[v];
  const auto fan = mesh_.Outgoing(v);
  if (o.via == Via::kWindow) {
    const Window& w = windows_[o.id];
    const HalfEdgeFrame& f = frame_[w.h];
    // v = C of the window's face; its corner there starts at C->A.
    const int32_t corner = Mesh::Prev(w.h);
    const double ax = -f.cx, ay = -f.cy;              // A - C
    const double sx = w.sx - f.cx, sy = w.sy - f.cy;  // S - C
    const double beta = std::atan2(ax * sy - ay * sx, ax * sx + ay * sy);
    double phi = 0;
    for (const int32_t h : fan) {
      if (h == corner) return phi + std::clamp(beta, 0.0, corner_angle_[h]);
      phi += corner_angle_[h];
    }
  } else if (o.via == Via::kVertex) {
    double phi = 0;
    for (const int32_t h : fan) {
      if (mesh_.Dest(h) == o.id) return phi;
      phi += corner_angle_[h];
    }
    if (mesh_.Opposite(fan.back()) == o.id) return phi;  // end of a boundary fan
  }
  return -1;  // no single incoming direction: emit everywhere
}

void ExactGeodesicSolver::EmitFromVertex(int32_t v) {
  const double d = dist_[v];
  const int32_t source = nearest_[v];
  const auto fan = mesh_.Outgoing(v);
  for (const int32_t o : fan) {
    if (!InRegion(Mesh::FaceOf(o))) continue;
    UpdateVertex(mesh_.Dest(o), d + mesh_.Length(o), source, Via::kVertex, v);
    UpdateVertex(mesh_.Opposite(o), d + mesh_.Length(Mesh::Prev(o)), source, Via::kVertex, v);
  }
  // A shortest path continues through a saddle or boundary vertex only into
  // its shadow: directions at least pi away, both ways round, from the
  // direction it came from (Mitchell, Mount & Papadimitriou 1987).
  double total = 0;
  for (const int32_t o : fan) total += corner_angle_[o];
  // On the border of a face region the vertex bounds the region as a
  // boundary vertex does, with a fan in pieces: emitting everywhere is a
  // superset of its shadow (every window stands for an actual path).
  const double back = RegionBorderState(v) != kInsideRegion ? -1 : BackAngle(v);
  std::array<std::pair<double, double>, 3> shadow;
  int num_shadow = 0;
  constexpr double kMargin = 1e-9;
  if (back < 0) {
    shadow[num_shadow++] = {-1, total + 1};
  } else if (mesh_.IsBoundaryVertex(v)) {
    if (back - std::numbers::pi > 0) shadow[num_shadow++] = {-1, back - std::numbers::pi + kMargin};
    if (back + std::numbers::pi < total) {
      shadow[num_shadow++] = {back + std::numbers::pi - kMargin, total + 1};
    }
  } else {
    const double lo = back + std::numbers::pi - kMargin;
    const double hi = back + total - std::numbers::pi + kMargin;
    if (hi > lo) {
      // The range may wrap around the fan: also test it shifted by -total.
      shadow[num_shadow++] = {lo, hi};
      shadow[num_shadow++] = {lo - total, hi - total};
    }
  }
  double phi = 0;
  for (const int32_t o : fan) {
    const double theta = corner_angle_[o];
    const int32_t g = Mesh::Next(o);  // the edge opposite v in this face
    const int32_t t = InRegion(Mesh::FaceOf(o)) ? mesh_.Twin(g) : kNone;
    for (int k = 0; k < num_shadow && t != kNone; ++k) {
      const double a0 = std::max(shadow[k].first - phi, 0.0);
      const double a1 = std::min(shadow[k].second - phi, theta);
      if (!(a1 > a0)) continue;
      // Fraction along Dest(o) -> Opposite(o) hit by the ray at angle a.
      const HalfEdgeFrame& fo = frame_[o];
      auto hit = [&](double a) {
        if (a <= 0) return 0.0;
        if (a >= theta) return 1.0;
        const double c = std::cos(a), s = std::sin(a);
        const double den = c * fo.cy - s * (fo.cx - fo.length);
        return den > 0 ? std::clamp(fo.length * s / den, 0.0, 1.0) : 1.0;
      };
      const HalfEdgeFrame& fg = frame_[g];
      Window win{};
      win.b0 = (1 - hit(a1)) * fg.length;
      win.b1 = (1 - hit(a0)) * fg.length;
      win.sx = fg.length - fg.cx;
      win.sy = -fg.cy;
      win.sigma = d;
      win.h = t;
      win.parent = kNone;
      win.pseudo = v;
      win.source = source;
      PushWindow(win);
    }
    phi += theta;
  }
}

void ExactGeodesicSolver::UpdateVertex(int32_t v, double d, int32_t source, Via via, int32_t id) {
  if (!(d < dist_[v])) return;
  Touch(v);
  dist_[v] = d;
  nearest_[v] = source;
  origin_[v] = {via, id};
  if ((emits_[v] || RegionBorderState(v) == kReflexBorder) && d <= stop_radius_ &&
      !(d + (mesh_.position(v) - prune_point_).norm() > prune_length_)) {
    queue_.Push(d, ~v);
  }
}

double ExactGeodesicSolver::MinDistance(const Window& w) const {
  const double dx = w.sx < w.b0 ? w.b0 - w.sx : (w.sx > w.b1 ? w.sx - w.b1 : 0.0);
  return w.sigma + Hypot(dx, w.sy);
}

bool ExactGeodesicSolver::MayReachPrunePoint(const Window& w) const {
  // The prune point's coordinates about the edge's line: u along it from
  // its origin, r from the line (turned into the plane of the window).
  const mesh::Vec3& o = mesh_.position(mesh_.Origin(w.h));
  const double length = frame_[w.h].length;
  if (!(length > 0)) return true;
  const mesh::Vec3 axis = (mesh_.position(mesh_.Dest(w.h)) - o) / length;
  const mesh::Vec3 rel = prune_point_ - o;
  const double u = rel.dot(axis), r = rel.cross(axis).norm();
  // min over x in [b0, b1] of |S - x| + |x - Q|: convex in x; on the whole
  // line the minimum is where the segment from S to Q unfolded across the
  // line meets it.
  const double sr = std::abs(w.sy), total = sr + r;
  const double x = std::clamp(total > 0 ? w.sx + (u - w.sx) * (sr / total) : w.sx, w.b0, w.b1);
  return w.sigma + Hypot(x - w.sx, sr) + Hypot(u - x, r) <= prune_length_;
}

bool ExactGeodesicSolver::IsUseless(const Window& w) const {
  return CornersReachSooner(frame_[w.h], dist_[mesh_.Origin(w.h)], dist_[mesh_.Dest(w.h)],
                            dist_[mesh_.Opposite(w.h)], w.b0, w.b1, w.sx, w.sy, w.sigma);
}

void ExactGeodesicSolver::PushWindow(const Window& w) {
  if (!InRegion(Mesh::FaceOf(w.h))) {
    // Before every filter: the corners of the face beyond are not reached
    // inside the region, so they cannot stand in for the window.
    border_windows_.push_back({w.h, w.b0, w.b1, w.sx, w.sy, w.sigma});
    return;
  }
  if (!(w.b1 - w.b0 > 1e-14 * frame_[w.h].length)) return;
  const double key = MinDistance(w);
  if (key > stop_radius_) return;
  if (prune_length_ < kInfinity && !MayReachPrunePoint(w)) return;
  if (IsUseless(w)) return;
  const int32_t index = static_cast<int32_t>(windows_.size());
  windows_.push_back(w);
  if (edge_head_[w.h] == kNone) touched_halfedges_.push_back(w.h);
  windows_.back().next_on_edge = edge_head_[w.h];
  edge_head_[w.h] = index;
  ++stats_.windows_created;
  queue_.Push(key, index);
}

void ExactGeodesicSolver::PropagateWindow(int32_t index) {
  const Window w = windows_[index];
  const int32_t h = w.h;
  const HalfEdgeFrame& f = frame_[h];
  // Where the ray from the pseudo-source through C crosses this edge.
  const double xc = RayThroughC(f, w.sx, w.sy);
  const double eps = 1e-12 * f.length;
  if (xc >= w.b0 - eps && xc <= w.b1 + eps) {
    UpdateVertex(mesh_.Opposite(h), w.sigma + Hypot(f.cx - w.sx, f.cy - w.sy), w.source,
                 Via::kWindow, index);
  }

  // ICH's "one angle, one split" (Xin & Wang 2009, after Chen & Han): keep,
  // per face angle, the shortest segment P*->C seen through this edge. A ray
  // of this window that crosses that segment reaches the crossing point later
  // than the segment's own path whenever sigma + |S C| exceeds d*(C): such
  // rays are trimmed from the children.
  const double dc_here = w.sigma + Hypot(f.cx - w.sx, f.cy - w.sy);
  double left_end = std::min(w.b1, xc);     // rays through [b0, left_end] go left
  double right_begin = std::max(w.b0, xc);  // rays through [right_begin, b1] go right
  Split& split = split_[h];
  if (split.dc + kFilterSlack * dc_here < dc_here) {
    if (split.x < xc) {
      left_end = std::min(left_end, split.x);
    } else {
      right_begin = std::max(right_begin, split.x);
    }
  }
  if (xc >= w.b0 && xc <= w.b1 && dc_here < split.dc) split = {dc_here, xc};

  Window child{};
  child.sigma = w.sigma;
  child.parent = index;
  child.pseudo = kNone;
  child.source = w.source;

  // Rays through [b0, left_end] leave through edge A->C (A = origin), those
  // through [right_begin, b1] through C->B.
  if (w.b0 < left_end) {
    const int32_t t = mesh_.Twin(Mesh::Prev(h));
    if (t != kNone) {
      const ChildWindow c = ChildAcrossAC(f, frame_[t].length, w.sx, w.sy, xc, w.b0, left_end);
      child.b0 = c.b0, child.b1 = c.b1, child.sx = c.sx, child.sy = c.sy, child.h = t;
      PushWindow(child);
    }
  }
  if (right_begin < w.b1) {
    const int32_t t = mesh_.Twin(Mesh::Next(h));
    if (t != kNone) {
      const ChildWindow c = ChildAcrossCB(f, frame_[t].length, w.sx, w.sy, xc, right_begin, w.b1);
      child.b0 = c.b0, child.b1 = c.b1, child.sx = c.sx, child.sy = c.sy, child.h = t;
      PushWindow(child);
    }
  }
}

bool ExactGeodesicSolver::TargetsSettled(double key) const {
  for (int32_t v : stop_vertices_) {
    if (dist_[v] > key) return false;
  }
  for (const SurfacePoint& p : stop_points_) {
    if (UpperBoundAt(p) > key) return false;
  }
  return true;
}

std::array<double, 2> ExactGeodesicSolver::InFrame(int32_t h, const SurfacePoint& p) const {
  return geodesic::InFrame(frame_[h], h, p);
}

double ExactGeodesicSolver::UpperBoundAt(const SurfacePoint& p) const { return BestAt(p).distance; }

ExactGeodesicSolver::Candidate ExactGeodesicSolver::BestAt(const SurfacePoint& p) const {
  Candidate best;
  const Vec3 x = mesh::PositionOf(mesh_, p);
  for (int i = 0; i < 3; ++i) {
    const int32_t v = mesh_.face(p.face)[i];
    const double d = dist_[v] + (mesh_.position(v) - x).norm();
    if (d < best.distance) best = {d, Via::kVertex, v};
  }
  for (const SourceInFace& s : face_sources_) {
    if (s.face != p.face) continue;
    const double d = (s.position - x).norm();
    if (d < best.distance) best = {d, Via::kSource, s.source};
  }
  for (int i = 0; i < 3; ++i) {
    const int32_t h = 3 * p.face + i;
    const auto [px, py] = InFrame(h, p);
    const double eps = 1e-12 * frame_[h].length;
    for (int32_t k = edge_head_[h]; k != kNone; k = windows_[k].next_on_edge) {
      const Window& w = windows_[k];
      const double den = py - w.sy;
      if (!(den > 0)) continue;
      const double cross = w.sx + (px - w.sx) * (-w.sy) / den;
      if (cross < w.b0 - eps || cross > w.b1 + eps) continue;
      const double d = w.sigma + Hypot(px - w.sx, py - w.sy);
      if (d < best.distance) best = {d, Via::kWindow, k};
    }
  }
  return best;
}

double ExactGeodesicSolver::DistanceAt(const SurfacePoint& p) const { return BestAt(p).distance; }

absl::StatusOr<std::vector<SurfacePoint>> ExactGeodesicSolver::PathTo(const SurfacePoint& p) const {
  GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(mesh_, p));
  std::vector<SurfacePoint> path = {p};
  Candidate c = BestAt(p);
  if (!(c.distance < kInfinity)) {
    return absl::NotFoundError("the point is not reachable from any source");
  }
  auto vertex_point = [&](int32_t v) { return *mesh::VertexPoint(mesh_, v); };
  // Current position, as a point of a face, while following windows back.
  SurfacePoint here = p;
  const int64_t max_steps = 4 * int64_t{mesh_.num_halfedges()} + 16;
  for (int64_t step = 0; step < max_steps; ++step) {
    switch (c.via) {
      case Via::kSource:
        path.push_back(sources_[c.id]);
        return path;
      case Via::kInitial:
        return absl::FailedPreconditionError(
            "the path reaches a vertex whose distance was given as initial_distance");
      case Via::kNone:
        return absl::InternalError("path tracing lost its way");
      case Via::kVertex: {
        const int32_t v = c.id;
        const SurfacePoint vp = vertex_point(v);
        path.push_back(vp);
        here = vp;
        c = {dist_[v], origin_[v].via, origin_[v].id};
        if (c.via == Via::kWindow) {
          // The vertex is the opposite corner of the window's face.
          const int32_t h = windows_[c.id].h;
          here.face = Mesh::FaceOf(h);
          here.w = {0, 0, 0};
          here.w[(h + 2) % 3] = 1.0;
        } else if (c.via == Via::kSource) {
          // A vertex source, or a vertex of a face holding the source.
          const SurfacePoint& s = sources_[c.id];
          const bool same = (PositionOf(mesh_, s) - mesh_.position(v)).norm() == 0;
          if (!same) path.push_back(s);
          return path;
        }
        break;
      }
      case Via::kWindow: {
        const Window& w = windows_[c.id];
        const auto [px, py] = InFrame(w.h, here);
        const double den = py - w.sy;
        double cross = den > 0 ? w.sx + (px - w.sx) * (-w.sy) / den : w.sx;
        cross = std::clamp(cross, w.b0, w.b1);
        const double l = frame_[w.h].length;
        SurfacePoint q;
        q.face = Mesh::FaceOf(w.h);
        q.w = {0, 0, 0};
        q.w[w.h % 3] = 1.0 - cross / l;
        q.w[(w.h + 1) % 3] = cross / l;
        path.push_back(q);
        if (w.parent != kNone) {
          // Continue in the parent's face, where this edge is twin(w.h).
          const int32_t g = mesh_.Twin(w.h);
          here.face = Mesh::FaceOf(g);
          here.w = {0, 0, 0};
          here.w[g % 3] = cross / l;  // Origin(g) = Dest(w.h)
          here.w[(g + 1) % 3] = 1.0 - cross / l;
          c = {0, Via::kWindow, w.parent};
        } else if (w.pseudo != kNone) {
          c = {0, Via::kVertex, w.pseudo};
        } else {
          c = {0, Via::kSource, w.source};
        }
        break;
      }
    }
  }
  return absl::InternalError("path tracing did not terminate");
}

absl::StatusOr<std::vector<double>> ExactGeodesicDistances(const Mesh& mesh,
                                                           std::span<const SurfacePoint> sources,
                                                           const GeodesicOptions& options) {
  ExactGeodesicSolver solver(mesh);
  GEODEX_RETURN_IF_ERROR(solver.Propagate(sources, options));
  return solver.VertexDistances();
}

}  // namespace geodex::geodesic
