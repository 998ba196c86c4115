#include "core/geodesic/vertex_geodesic.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::geodesic {
namespace {

using mesh::kNone;
using mesh::Vec3;

// Vertices whose angle sum exceeds 2*pi by more than this are saddles
// (pseudo-sources). Flat vertices are not: a geodesic runs straight through
// them, and the window split at the ray through a vertex hands that ray to
// both sides, so nothing is lost. Treating them as saddles (as VTP and the
// window engine do, against rounding) costs dearly where they abound: on a
// mesh subdivided flat, three vertices in four are flat, and every one would
// emit windows all round (tests/bench/exact_geodesics.md, the wavefront engine).
// A true saddle within this of flat hides a shadow of relative size ~1e-9.
constexpr double kSaddleSlack = 1e-9;
// Two crossings of an edge closer than this fraction of its length are the
// same point for the "two sides" rule, which then keeps both sides.
constexpr double kSideSlack = 1e-8;

// Whether the segments from the pseudo-sources p and q to the points (a,0) and
// (b,0) of the edge cross (touching counts) below it. By orientation tests:
// no division, and exact in sign up to rounding.
inline double Orient(double ox, double oy, double ax, double ay, double bx, double by) {
  return (ax - ox) * (by - oy) - (ay - oy) * (bx - ox);
}
bool CrossBelowEdge(double px, double py, double a, double qx, double qy, double b) {
  const double o1 = Orient(px, py, a, 0, qx, qy);
  const double o2 = Orient(px, py, a, 0, b, 0);
  if ((o1 > 0 && o2 > 0) || (o1 < 0 && o2 < 0)) return false;
  const double o3 = Orient(qx, qy, b, 0, px, py);
  const double o4 = Orient(qx, qy, b, 0, a, 0);
  return !((o3 > 0 && o4 > 0) || (o3 < 0 && o4 < 0));
}

}  // namespace

VertexGeodesicSolver::VertexGeodesicSolver(const Mesh& mesh)
    : mesh_(mesh), frame_(HalfEdgeFrames(mesh)) {
  const int32_t nh = mesh.num_halfedges();
  emits_.resize(mesh.num_vertices());
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    // A pinch (an end of an edge of length 0, kept by mesh repair) is a
    // cone point of unknown angle: a pseudo-source, to be safe.
    emits_[v] =
        mesh.IsReferenced(v) && (mesh.IsBoundaryVertex(v) || mesh::TouchesZeroLengthEdge(mesh, v) ||
                                 mesh.AngleSum(v) > 2 * std::numbers::pi + kSaddleSlack);
  }
  head_.assign(nh, kNone);
  queued_.assign(nh, 0);
  target_begin_.assign(mesh.num_faces(), -1);
}

void VertexGeodesicSolver::Reset() {
  dist_.assign(mesh_.num_vertices(), kInfinity);
  nearest_.assign(mesh_.num_vertices(), kNone);
  state_.assign(mesh_.num_vertices(), kOutside);
  vertex_queue_.Clear();
  // Lists are empty after every propagation that ran to its end; after one
  // that stopped on an error, start afresh.
  if (live_ != 0) {
    std::fill(head_.begin(), head_.end(), kNone);
    std::fill(queued_.begin(), queued_.end(), 0);
  }
  pool_.clear();
  free_ = kNone;
  live_ = 0;
  fifo_.clear();
  face_sources_.clear();
  for (const int32_t f : target_faces_) target_begin_[f] = -1;
  target_faces_.clear();
  targets_.clear();
  target_dist_.clear();
  stats_ = {};
}

absl::Status VertexGeodesicSolver::Propagate(std::span<const int32_t> sources,
                                             const VertexGeodesicOptions& options) {
  Reset();
  if (sources.empty()) return absl::InvalidArgumentError("no sources given");
  for (const int32_t v : sources) {
    if (v < 0 || v >= mesh_.num_vertices()) {
      return absl::OutOfRangeError(
          absl::StrFormat("source vertex %d out of range [0, %d)", v, mesh_.num_vertices()));
    }
    if (!mesh_.IsReferenced(v)) {
      return absl::InvalidArgumentError(absl::StrFormat("source vertex %d belongs to no face", v));
    }
  }
  GEODEX_RETURN_IF_ERROR(Start(options));
  for (int32_t s = 0; s < static_cast<int32_t>(sources.size()); ++s) {
    UpdateVertex(sources[s], 0.0, s);
  }
  return Run();
}

absl::Status VertexGeodesicSolver::Propagate(std::span<const SurfacePoint> sources,
                                             const VertexGeodesicOptions& options) {
  Reset();
  if (sources.empty()) return absl::InvalidArgumentError("no sources given");
  for (const SurfacePoint& p : sources) {
    GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(mesh_, p));
  }
  GEODEX_RETURN_IF_ERROR(Start(options));
  for (int32_t s = 0; s < static_cast<int32_t>(sources.size()); ++s) {
    const SurfacePoint& p = sources[s];
    const SourcePlace place = ClassifySource(mesh_, p);
    if (place.kind == SourcePlace::kVertex) {
      UpdateVertex(place.vertex, 0.0, s);
    } else if (place.kind == SourcePlace::kFace) {
      AddFaceSource(p.face, place.w, s, kNone);
    } else {
      // On an edge: both faces hold the source, and neither sends windows
      // across the edge itself.
      const int32_t h = place.halfedge;
      AddFaceSource(p.face, place.w, s, h);
      const int32_t g = mesh_.Twin(h);
      if (g != kNone) AddFaceSource(Mesh::FaceOf(g), WeightsInTwin(h, g, place.w), s, g);
    }
  }
  return Run();
}

absl::Status VertexGeodesicSolver::Start(const VertexGeodesicOptions& options) {
  GEODEX_RETURN_IF_ERROR(CheckInitialDistances(options.initial_distance, mesh_.num_vertices()));
  if (!options.initial_distance.empty()) {
    std::copy(options.initial_distance.begin(), options.initial_distance.end(), dist_.begin());
  }
  for (const SurfacePoint& q : options.targets) {
    GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(mesh_, q));
  }
  targets_.assign(options.targets.begin(), options.targets.end());
  target_dist_.assign(targets_.size(), kInfinity);
  target_order_.resize(targets_.size());
  for (size_t i = 0; i < targets_.size(); ++i) target_order_[i] = static_cast<int32_t>(i);
  std::stable_sort(target_order_.begin(), target_order_.end(),
                   [&](int32_t a, int32_t b) { return targets_[a].face < targets_[b].face; });
  for (size_t k = 0; k < target_order_.size(); ++k) {
    const int32_t f = targets_[target_order_[k]].face;
    if (target_begin_[f] < 0) {
      target_begin_[f] = static_cast<int32_t>(k);
      target_faces_.push_back(f);
    }
  }
  max_windows_ = options.max_windows > 0 ? options.max_windows
                                         : 400 * int64_t{mesh_.num_halfedges()} + 1'000'000;
  return absl::OkStatus();
}

absl::Status VertexGeodesicSolver::Run() {
  while (!vertex_queue_.empty()) {
    const auto [d, v] = vertex_queue_.Pop();
    if (d != dist_[v]) continue;  // superseded by a shorter path
    Settle(v);
    // Lists enqueued while these propagate are appended and taken in turn.
    for (size_t i = 0; i < fifo_.size(); ++i) {
      // The first window of the next list is otherwise a cache miss.
      if (i + 1 < fifo_.size() && head_[fifo_[i + 1]] != kNone) {
        __builtin_prefetch(&pool_[head_[fifo_[i + 1]]]);
      }
      PropagateList(fifo_[i]);
    }
    fifo_.clear();
    if (stats_.windows_created > max_windows_) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "geodesic propagation on %s exceeded %d windows", mesh_.name(), max_windows_));
    }
  }
  FinishTargets();
  return absl::OkStatus();
}

void VertexGeodesicSolver::AddFaceSource(int32_t face, const std::array<double, 3>& w,
                                         int32_t source, int32_t skip_halfedge) {
  const SurfacePoint p{face, w};
  const Vec3 x = mesh::PositionOf(mesh_, p);
  face_sources_.push_back({face, source, x});
  for (int i = 0; i < 3; ++i) {
    const int32_t v = mesh_.face(face)[i];
    UpdateVertex(v, (mesh_.position(v) - x).norm(), source);
  }
  for (int i = 0; i < 3; ++i) {
    const int32_t h = 3 * face + i;
    const int32_t t = mesh_.Twin(h);
    if (h == skip_halfedge || t == kNone) continue;
    const auto [px, py] = InFrame(h, p);
    const double l = frame_[h].length;
    Window win;
    win.b0 = 0;
    win.b1 = l;
    win.sx = l - px;  // mirrored into the twin's frame
    win.sy = -py;
    win.sigma = 0;
    win.source = source;
    AddWindow(t, win);
  }
}

std::array<double, 2> VertexGeodesicSolver::InFrame(int32_t h, const SurfacePoint& p) const {
  return geodesic::InFrame(frame_[h], h, p);
}

void VertexGeodesicSolver::EvaluateTargets(int32_t h) {
  const int32_t f = Mesh::FaceOf(h);
  const double eps = 1e-12 * frame_[h].length;
  for (size_t k = target_begin_[f];
       k < target_order_.size() && targets_[target_order_[k]].face == f; ++k) {
    const int32_t i = target_order_[k];
    const auto [px, py] = InFrame(h, targets_[i]);
    for (const Pending& p : pending_) {
      const Window& w = p.window;
      const double den = py - w.sy;
      if (!(den > 0)) continue;
      const double cross = w.sx + (px - w.sx) * (-w.sy) / den;
      if (cross < w.b0 - eps || cross > w.b1 + eps) continue;
      target_dist_[i] = std::min(target_dist_[i], w.sigma + Hypot(px - w.sx, py - w.sy));
    }
  }
}

void VertexGeodesicSolver::FinishTargets() {
  // Paths through a corner of the target's face, or straight from a source
  // inside that face; the windows that enter it were seen as they passed.
  for (size_t i = 0; i < targets_.size(); ++i) {
    const SurfacePoint& q = targets_[i];
    const Vec3 x = mesh::PositionOf(mesh_, q);
    for (const int32_t v : mesh_.face(q.face)) {
      if (nearest_[v] == kNone) continue;
      target_dist_[i] = std::min(target_dist_[i], dist_[v] + (mesh_.position(v) - x).norm());
    }
    for (const SourceInFace& s : face_sources_) {
      if (s.face == q.face) target_dist_[i] = std::min(target_dist_[i], (s.position - x).norm());
    }
  }
  for (const int32_t f : target_faces_) target_begin_[f] = -1;
  target_faces_.clear();
}

void VertexGeodesicSolver::UpdateVertex(int32_t v, double d, int32_t source) {
  if (!(d < dist_[v])) return;
  dist_[v] = d;
  nearest_[v] = source;
  // A settled vertex that got closer is settled again only if it emits
  // windows of its own; elsewhere the windows that found the shorter path go
  // on carrying it.
  if (state_[v] != kInside) {
    state_[v] = kFront;
    vertex_queue_.Push(d, v);
  } else if (emits_[v]) {
    vertex_queue_.Push(d, v);
  }
}

void VertexGeodesicSolver::Settle(int32_t v) {
  ++stats_.vertices_settled;
  state_[v] = kInside;
  const auto fan = mesh_.Outgoing(v);
  for (const int32_t o : fan) {
    for (const int32_t u : {mesh_.Dest(o), mesh_.Opposite(o)}) {
      if (state_[u] == kOutside) state_[u] = kFront;
    }
  }
  // A vertex that kept its initial distance is settled only to let the
  // windows past it (see WakeEnd); it emits nothing of its own.
  if (nearest_[v] != kNone && (emits_[v] || dist_[v] == 0)) EmitFrom(v);
  // The lists on the edges at v may now cross their faces; so may the lists
  // on the edges opposite v, from either side, once the vertex beyond them
  // has been reached.
  for (const int32_t o : fan) {
    Enqueue(o);
    Enqueue(Mesh::Prev(o));
    const int32_t g = Mesh::Next(o);
    const int32_t t = mesh_.Twin(g);
    if (t == kNone || state_[mesh_.Opposite(t)] != kOutside) {
      Enqueue(g);
      if (t != kNone) Enqueue(t);
    }
  }
}

void VertexGeodesicSolver::EmitFrom(int32_t v) {
  const double d = dist_[v];
  const int32_t source = nearest_[v];
  for (const int32_t o : mesh_.Outgoing(v)) {
    UpdateVertex(mesh_.Dest(o), d + mesh_.Length(o), source);
    UpdateVertex(mesh_.Opposite(o), d + mesh_.Length(Mesh::Prev(o)), source);
  }
  // Unlike ExactGeodesicSolver, no shadow cone: the incoming direction is not
  // kept, and the filters drop what a vertex already reaches sooner.
  for (const int32_t o : mesh_.Outgoing(v)) {
    const int32_t g = Mesh::Next(o);  // the edge opposite v in this face
    const int32_t t = mesh_.Twin(g);
    if (t == kNone) continue;
    const HalfEdgeFrame& fg = frame_[g];
    Window w;
    w.b0 = 0;
    w.b1 = fg.length;
    w.sx = fg.length - fg.cx;  // v, mirrored into the twin's frame
    w.sy = -fg.cy;
    w.sigma = d;
    w.source = source;
    AddWindow(t, w);
  }
}

bool VertexGeodesicSolver::IsUseless(int32_t h, const Window& w) const {
  return CornersReachSooner(frame_[h], dist_[mesh_.Origin(h)], dist_[mesh_.Dest(h)],
                            dist_[mesh_.Opposite(h)], w.b0, w.b1, w.sx, w.sy, w.sigma);
}

int32_t VertexGeodesicSolver::Allocate() {
  ++live_;
  stats_.peak_windows = std::max(stats_.peak_windows, live_);
  if (free_ != kNone) {
    const int32_t k = free_;
    free_ = pool_[k].next;
    return k;
  }
  pool_.emplace_back();
  return static_cast<int32_t>(pool_.size() - 1);
}

void VertexGeodesicSolver::Free(int32_t k) {
  --live_;
  pool_[k].next = free_;
  free_ = k;
}

void VertexGeodesicSolver::AddWindow(int32_t h, const Window& w) {
  if (!(w.b1 - w.b0 > 1e-14 * frame_[h].length)) return;
  ++stats_.windows_created;
  const int32_t k = Allocate();
  pool_[k] = w;
  pool_[k].next = head_[h];
  head_[h] = k;
  const int32_t a = mesh_.Origin(h), b = mesh_.Dest(h);
  if (state_[a] == kInside || state_[b] == kInside) {
    Enqueue(h);
  } else {
    WakeEnd(a);
    WakeEnd(b);
  }
}

void VertexGeodesicSolver::WakeEnd(int32_t v) {
  // A window waits on its edge until an end of the edge is settled. An end
  // that this propagation does not improve on its initial distance would
  // never be queued, yet the window may still improve vertices beyond it
  // (the region a new source improves is star-shaped along geodesics, but
  // its vertices need not be): queue such an end at its initial distance.
  if (state_[v] != kInside && state_[v] != kWoken && nearest_[v] == kNone && dist_[v] < kInfinity) {
    state_[v] = kWoken;
    vertex_queue_.Push(dist_[v], v);
  }
}

void VertexGeodesicSolver::Enqueue(int32_t h) {
  if (queued_[h] || head_[h] == kNone) return;
  queued_[h] = 1;
  fifo_.push_back(h);
}

void VertexGeodesicSolver::PropagateList(int32_t h) {
  queued_[h] = 0;
  int32_t k = head_[h];
  if (k == kNone) return;
  head_[h] = kNone;
  ++stats_.lists_propagated;
  const HalfEdgeFrame& f = frame_[h];
  const int32_t c = mesh_.Opposite(h);

  // Pass 1: drop what the face's vertices reach sooner.
  pending_.clear();
  while (k != kNone) {
    // The list's windows are copied out and their slots freed at once: the
    // passes below then read contiguous memory, and the children reuse the
    // slots while they are still in cache.
    const int32_t next = pool_[k].next;
    if (next != kNone) __builtin_prefetch(&pool_[next]);
    if (!IsUseless(h, pool_[k])) pending_.push_back({pool_[k], 0, 0});
    Free(k);
    k = next;
  }
  if (target_begin_[Mesh::FaceOf(h)] >= 0) EvaluateTargets(h);
  // Pass 2: drop or trim what a neighbour in the list reaches sooner.
  PruneNeighbours();
  // Pass 3: find the window that reaches C soonest.
  double best = kInfinity;
  int32_t best_source = kNone;
  double best_crossing = 0, best_sx = 0, best_sy = 0;
  for (Pending& p : pending_) {
    const Window& w = p.window;
    p.xc = RayThroughC(f, w.sx, w.sy);
    p.crossing = std::clamp(p.xc, w.b0, w.b1);
    // Straight to C when the ray through C crosses the interval, else
    // round its nearer end: either way the length of a path to C.
    const double dc = w.sigma + Hypot(p.crossing - w.sx, w.sy) + Hypot(f.cx - p.crossing, f.cy);
    if (dc < best) {
      best = dc;
      best_source = w.source;
      best_crossing = p.crossing;
      best_sx = w.sx;
      best_sy = w.sy;
    }
  }
  if (best < dist_[c]) UpdateVertex(c, best, best_source);

  // Pass 4: "one angle, two sides" (VTP, Rule 1). Let P be the list's
  // soonest path to C, crossing the edge at p. A window whose own route to C
  // crosses left of p sends its rays right of C across P: inside the face
  // when they enter left of p (and there P reaches the crossing no later,
  // since it reaches C no later), below the edge when its ray through b1
  // meets P there. Either way those rays are no shorter than P and are not
  // propagated; mirrored for the right.
  const double side_slack = kSideSlack * f.length;
  for (const Pending& p : pending_) {
    const Window& w = p.window;
    bool left = true, right = true;
    if (p.crossing < best_crossing - side_slack) {
      right = !(w.b1 < best_crossing ||
                CrossBelowEdge(best_sx, best_sy, best_crossing, w.sx, w.sy, w.b1));
    } else if (p.crossing > best_crossing + side_slack) {
      left = !(w.b0 > best_crossing ||
               CrossBelowEdge(best_sx, best_sy, best_crossing, w.sx, w.sy, w.b0));
    }
    // Rays through [b0, xc] leave through A->C, those through [xc, b1]
    // through C->B.
    if (left && w.b0 < std::min(w.b1, p.xc)) {
      if (const int32_t t = mesh_.Twin(Mesh::Prev(h)); t != kNone) {
        PropagateChild(
            t, ChildAcrossAC(f, frame_[t].length, w.sx, w.sy, p.xc, w.b0, std::min(w.b1, p.xc)), w);
      }
    }
    if (right && std::max(w.b0, p.xc) < w.b1) {
      if (const int32_t t = mesh_.Twin(Mesh::Next(h)); t != kNone) {
        PropagateChild(
            t, ChildAcrossCB(f, frame_[t].length, w.sx, w.sy, p.xc, std::max(w.b0, p.xc), w.b1), w);
      }
    }
  }
}

// VTP's Rule 2 on two windows of one edge, in the plane below it where both
// pseudo-sources lie. Take an end e of window a inside window b's interval,
// and suppose b's path to e crosses a's ray through its other end. Then every
// ray of a crosses b's path to e, and every ray of b through the far side of
// e crosses a's path to e. Where a reaches e later than b, a's rays meet b's
// path too late everywhere (a is dropped); where b reaches e later, b's rays
// beyond e do (b is trimmed at e). The crossing points see the same argument
// as ExactGeodesicSolver's "one split" rule.
VertexGeodesicSolver::PairVerdict VertexGeodesicSolver::ComparePair(Window& w1, Window& w2) const {
  auto distance = [](const Window& w, double x) { return w.sigma + Hypot(x - w.sx, w.sy); };
  constexpr double kTie = 1 - 1e-12;
  // An end of `a` inside `b`: `at` is that end, `far` a's other end.
  // Returns which of the two is dominated at `at`, if the geometry allows.
  enum Outcome { kNeither, kADominated, kBDominated };
  auto judge = [&](const Window& a, double at, double far, const Window& b) {
    if (!CrossBelowEdge(b.sx, b.sy, at, a.sx, a.sy, far)) return kNeither;
    const double da = distance(a, at), db = distance(b, at);
    if (db < da * kTie) return kADominated;
    if (da < db * kTie) return kBDominated;
    return kNeither;
  };
  if (w1.b0 >= w2.b0 && w1.b0 <= w2.b1) {
    const Outcome o = judge(w1, w1.b0, w1.b1, w2);
    if (o == kADominated) return PairVerdict::kFirstDominated;
    if (o == kBDominated) w2.b0 = w1.b0;
  }
  if (w1.b1 >= w2.b0 && w1.b1 <= w2.b1) {
    const Outcome o = judge(w1, w1.b1, w1.b0, w2);
    if (o == kADominated) return PairVerdict::kFirstDominated;
    if (o == kBDominated) w2.b1 = w1.b1;
  }
  if (w2.b0 >= w1.b0 && w2.b0 <= w1.b1) {
    const Outcome o = judge(w2, w2.b0, w2.b1, w1);
    if (o == kADominated) return PairVerdict::kSecondDominated;
    if (o == kBDominated) w1.b0 = w2.b0;
  }
  if (w2.b1 >= w1.b0 && w2.b1 <= w1.b1) {
    const Outcome o = judge(w2, w2.b1, w2.b0, w1);
    if (o == kADominated) return PairVerdict::kSecondDominated;
    if (o == kBDominated) w1.b1 = w2.b1;
  }
  return PairVerdict::kBoth;
}

void VertexGeodesicSolver::PruneNeighbours() {
  // Each window against the one before it among the survivors, as VTP walks
  // its list; after a drop the new neighbours are compared in turn.
  size_t kept = 0;
  for (size_t i = 0; i < pending_.size(); ++i) {
    pending_[kept++] = pending_[i];
    while (kept >= 2) {
      const PairVerdict verdict = ComparePair(pending_[kept - 2].window, pending_[kept - 1].window);
      if (verdict == PairVerdict::kBoth) break;
      if (verdict == PairVerdict::kFirstDominated) pending_[kept - 2] = pending_[kept - 1];
      --kept;
    }
  }
  pending_.resize(kept);
}

void VertexGeodesicSolver::PropagateChild(int32_t t, const ChildWindow& c, const Window& w) {
  Window child;
  child.b0 = c.b0;
  child.b1 = c.b1;
  child.sx = c.sx;
  child.sy = c.sy;
  child.sigma = w.sigma;
  child.source = w.source;
  AddWindow(t, child);
}

}  // namespace geodex::geodesic
