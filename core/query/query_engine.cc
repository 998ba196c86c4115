#include "core/query/query_engine.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <queue>
#include <tuple>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/geometry/unfolding.h"
#include "core/query/face_lift.h"
#include "core/query/unfold_kernel.h"

namespace geodex::query {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The face vertex of largest weight: the anchor of points of faces whose
// vertices lie in three different triangles.
inline int Heaviest(const SurfacePoint& p) {
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (p.w[i] > p.w[k]) k = i;
  }
  return k;
}

// Loads the first and last byte of [p, p + size) and discards them: a
// prefetch that works. Software prefetches of the ApproxLifts were found to
// be dropped (still missing L1 several pairs later, on a virtualised Zen 4);
// a load is not. The figures: tests/bench/README.md.
inline void Touch(const void* p, size_t size) {
  const char* c = static_cast<const char*>(p);
  asm volatile("" : : "r"(c[0]), "r"(c[size - 1]));
}

// sqrt(x^2 + y^2) without std::hypot's overflow care, which costs more than
// the rest of a query.
inline double Norm2(double x, double y) { return std::sqrt(x * x + y * y); }

using geometry::Place;
using geometry::Trilaterate;
using geometry::TwoSideDistance2;
using kernel::Frame;
using kernel::Placed;
using kernel::PlaceInTriangle;
using kernel::TwoSideToOutside2;

// Distances from a point of a mesh face to the three corners of a geodesic
// triangle, from the distances d[vertex][corner] of the face's vertices. The
// face lies in its plane (vertex 0 at the origin, vertex 1 at (l, 0), vertex 2
// at (cx, cy)), the point at (px, py). Exact distances of one field at the
// face's corners fix the field's unfolded source in that plane
// (Trilaterate).
inline void LiftInFace(double l, double cx, double cy, double px, double py, bool exact,
                       const double (&d)[3][3], std::array<double, 3>* out) {
  if (exact && cy > 1e-3 * l) {
    for (int c = 0; c < 3; ++c) {
      double sx, sy;
      Trilaterate(l, cx, cy, d[0][c], d[1][c], d[2][c], &sx, &sy);
      (*out)[c] = Norm2(px - sx, py - sy);
    }
    return;
  }
  // Paper §5.2, case 4: two-side unfolding about each edge of the face: the
  // point placed from its distances to the edge's ends, the corner mirrored
  // on the other side; the smallest over the edges. The point's placements
  // do not depend on the corner.
  const double to_vertex[3] = {Norm2(px, py), Norm2(px - l, py), Norm2(px - cx, py - cy)};
  const double edge[3] = {l, Norm2(cx - l, cy), Norm2(cx, cy)};
  double xp[3], yp[3];
  for (int i = 0; i < 3; ++i) {
    if (edge[i] > 0) Place(edge[i], to_vertex[i], to_vertex[(i + 1) % 3], &xp[i], &yp[i]);
  }
  for (int c = 0; c < 3; ++c) {
    double best = kInf;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      if (!(edge[i] > 0)) {
        best = std::min(best, (to_vertex[i] + d[i][c]) * (to_vertex[i] + d[i][c]));
        continue;
      }
      double xq, yq;
      Place(edge[i], d[i][c], d[j][c], &xq, &yq);
      best = std::min(best, TwoSideDistance2(xp[i], yp[i], xq, yq));
    }
    (*out)[c] = std::sqrt(best);
  }
}

}  // namespace

absl::StatusOr<std::shared_ptr<const QueryEngine>> QueryEngine::Create(
    std::shared_ptr<const index::Index> index, QueryOptions options) {
  if (index == nullptr) return absl::InvalidArgumentError("no index");
  if (index->num_triangles() == 0 || index->num_samples() == 0) {
    return absl::FailedPreconditionError("the index has no geodesic triangles");
  }
  std::shared_ptr<QueryEngine> engine(new QueryEngine(std::move(index), options));
  return std::shared_ptr<const QueryEngine>(std::move(engine));
}

QueryEngine::~QueryEngine() = default;

const QueryEngine::ApproxLift& QueryEngine::ApproxLiftOf(const FaceLift& fl, int heaviest) const {
  return approx_lifts_[fl.approx + (fl.anchors == 3 ? heaviest : 0)];
}

QueryEngine::QueryEngine(std::shared_ptr<const index::Index> index, QueryOptions options)
    : index_(std::move(index)),
      options_(options),
      view_{index_->positions(), index_->faces(), index_->twins()},
      matrix_(index_->sample_distances()),
      records_(index_->vertices()),
      triangles_(index_->triangles()),
      num_samples_(index_->num_samples()),
      locator_(index_->positions(), index_->faces(), index_->bvh_nodes(), index_->bvh_faces()) {
  frames_.resize(3 * triangles_.size());
  for (size_t t = 0; t < triangles_.size(); ++t) {
    const int32_t* c = triangles_[t].corner;
    for (int i = 0; i < 3; ++i) {
      const int32_t a = c[i], b = c[(i + 1) % 3], o = c[(i + 2) % 3];
      Frame<double>& e = frames_[3 * t + i];
      e.l = Matrix(a, b);
      if (e.l > 0) {
        Place(e.l, Matrix(a, o), Matrix(b, o), &e.cx, &e.cy);
        e.inv_2l = 1 / (2 * e.l);
      } else {
        e.cx = e.cy = e.inv_2l = 0;
      }
    }
  }
  face_lifts_.resize(index_->num_faces());
  double area = 0;
  for (int32_t f = 0; f < index_->num_faces(); ++f) {
    face_lifts_[f] = MakeFaceLift(f);
    const int32_t* v = &view_.faces[3 * f];
    area += 0.5 * (view_.Position(v[1]) - view_.Position(v[0]))
                      .cross(view_.Position(v[2]) - view_.Position(v[0]))
                      .norm();
  }
  scale_length_ = std::sqrt(2 * area / (std::sqrt(3.0) * num_samples_));
  refine_below_ = kRefineScale * scale_length_;
  // A pair whose O(1) answer overestimates lands above 3L while the pair is
  // closer: with a calibration, refine every pair that may be closer than 3L
  // (its answer minus the bound of answers between 3L and 5L).
  if (const index::AccuracyRecord* accuracy = index_->accuracy(); accuracy != nullptr) {
    constexpr int kBin = 4;  // [3L, 5L)
    static_assert(index::kAccuracyBinUpper[kBin - 1] == kRefineScale);
    const double margin =
        std::max(accuracy->unfold_bound[0][kBin], accuracy->unfold_bound[1][kBin]);
    if (margin > 0 && std::isfinite(margin)) refine_below_ += margin;
  }
}

absl::Status QueryEngine::Validate(const SurfacePoint& p) const {
  return mesh::ValidateSurfacePoint(index_->num_faces(), p, options_.weight_tolerance);
}

SurfacePoint QueryEngine::Canonical(const SurfacePoint& p) const {
  SurfacePoint c = p;
  double sum = 0;
  for (double& w : c.w) {
    w = std::max(w, 0.0);
    sum += w;
  }
  for (double& w : c.w) w /= sum;
  // A point on an edge is expressed in the face of lower id, so that both
  // descriptions of it give the same answers.
  int zeros = 0, zero = 0;
  for (int i = 0; i < 3; ++i) {
    if (c.w[i] == 0) {
      ++zeros;
      zero = i;
    }
  }
  if (zeros == 1) {
    const int32_t h = 3 * c.face + (zero + 1) % 3;  // the edge opposite the zero weight
    const int32_t g = view_.twins[h];
    if (g >= 0 && g / 3 < c.face) {
      SurfacePoint t{g / 3, {0, 0, 0}};
      t.w[g % 3] = c.w[(zero + 2) % 3];            // Origin(g) = Dest(h)
      t.w[(g % 3 + 1) % 3] = c.w[(zero + 1) % 3];  // Dest(g) = Origin(h)
      return t;
    }
  }
  return c;
}

SurfacePoint QueryEngine::InLowestFaceIfVertex(const SurfacePoint& c) const {
  int corner = -1;
  for (int i = 0; i < 3; ++i) {
    if (c.w[i] == 1) corner = i;
  }
  if (corner < 0) return c;
  const int32_t v = view_.Vertex(c.face, corner);
  struct LowestFace {  // FacesAround's output, keeping only the lowest id
    int32_t id;
    void push_back(int32_t f) { id = std::min(id, f); }
  } lowest{c.face};
  view_.FacesAround(v, c.face, &lowest);
  SurfacePoint t{lowest.id, {0, 0, 0}};
  t.w[view_.Corner(lowest.id, v)] = 1;
  return t;
}

double QueryEngine::ToSample(const LiftedPoint& p, int32_t s) const {
  for (int i = 0; i < 3; ++i) {
    if (p.corner[i] == s) return p.distance[i];  // paper §5.2, case 2.1
  }
  const Frame<double>* frames = &frames_[3 * p.triangle];
  const double e[3] = {Matrix(s, p.corner[0]), Matrix(s, p.corner[1]), Matrix(s, p.corner[2])};
  return std::sqrt(TwoSideToOutside2(frames, PlaceInTriangle(frames, p.distance.data()), e));
}

bool QueryEngine::FaceDistances(const int32_t* f, const LiftedPoint& anchor,
                                double (&d)[3][3]) const {
  // Exact for vertices of the anchor triangle, case 2.2 for the others.
  bool exact = true;
  for (int i = 0; i < 3; ++i) {
    const index::VertexRecord& r = records_[f[i]];
    if (r.triangle == anchor.triangle) {
      for (int c = 0; c < 3; ++c) d[i][c] = r.distance[c];
      continue;
    }
    exact = false;
    const LiftedPoint vi = VertexLift(f[i]);
    const Frame<double>* frames = &frames_[3 * vi.triangle];
    const Placed<double> placed = PlaceInTriangle(frames, vi.distance.data());
    for (int c = 0; c < 3; ++c) {
      const int32_t s = anchor.corner[c];
      d[i][c] = -1;
      for (int j = 0; j < 3; ++j) {
        if (vi.corner[j] == s) d[i][c] = vi.distance[j];
      }
      if (d[i][c] < 0) {
        const double e[3] = {Matrix(s, vi.corner[0]), Matrix(s, vi.corner[1]),
                             Matrix(s, vi.corner[2])};
        d[i][c] = std::sqrt(TwoSideToOutside2(frames, placed, e));
      }
    }
  }
  return exact;
}

QueryEngine::FaceFrame QueryEngine::FaceFrameOf(const int32_t* f) const {
  // The face in its own plane: v0 at the origin, v1 on the x axis.
  const mesh::Vec3 v0 = view_.Position(f[0]), e1 = view_.Position(f[1]) - v0,
                   e2 = view_.Position(f[2]) - v0;
  const double l = e1.norm();
  return {l, e1.dot(e2) / l, e1.cross(e2).norm() / l};
}

// Anchor on the geodesic triangle most of the face's vertices share (fewer
// approximate distances); when all three differ, on the triangle of the
// point's heaviest vertex (three ApproxLifts).
QueryEngine::FaceLift QueryEngine::MakeFaceLift(int32_t face) {
  const int32_t* f = &view_.faces[3 * face];
  FaceLift out;
  const FaceFrame frame = FaceFrameOf(f);
  const double edge[3] = {frame.l, std::hypot(frame.cx - frame.l, frame.cy),
                          std::hypot(frame.cx, frame.cy)};
  if (!(edge[0] > 0 && edge[1] > 0 && edge[2] > 0)) return out;  // SlowLift
  out.l = frame.l;
  out.cx = frame.cx;
  out.cy = frame.cy;
  const int32_t t0 = records_[f[0]].triangle, t1 = records_[f[1]].triangle,
                t2 = records_[f[2]].triangle;
  if (t0 != t1 && t0 != t2 && t1 != t2) {
    out.approx = static_cast<int32_t>(approx_lifts_.size());
    out.anchors = 3;
    for (int k = 0; k < 3; ++k) approx_lifts_.push_back(MakeApproxLift(f, frame, k));
    out.triangle = approx_lifts_[out.approx].triangle;
    return out;
  }
  const int k = t0 == t1 || t0 == t2 ? 0 : 1;
  const LiftedPoint anchor = VertexLift(f[k]);
  out.triangle = anchor.triangle;
  for (int c = 0; c < 3; ++c) out.corner[c] = anchor.corner[c];
  double d[3][3];
  if (FaceDistances(f, anchor, d) && frame.cy > 1e-3 * frame.l) {
    for (int c = 0; c < 3; ++c) {
      double sx, sy;
      Trilaterate(frame.l, frame.cx, frame.cy, d[0][c], d[1][c], d[2][c], &sx, &sy);
      out.src[c][0] = sx;
      out.src[c][1] = sy;
    }
    return out;
  }
  out.approx = static_cast<int32_t>(approx_lifts_.size());
  out.anchors = 1;
  approx_lifts_.push_back(MakeApproxLift(f, frame, k));
  return out;
}

QueryEngine::ApproxLift QueryEngine::MakeApproxLift(const int32_t* f, const FaceFrame& frame,
                                                    int k) const {
  const LiftedPoint anchor = VertexLift(f[k]);
  ApproxLift out;
  out.triangle = anchor.triangle;
  for (int c = 0; c < 3; ++c) out.corner[c] = anchor.corner[c];
  double d[3][3];
  FaceDistances(f, anchor, d);
  // Paper §5.2, case 4: corner c unfolded about face edge i (vertex i to
  // vertex i+1) from its distances to the edge's ends, on the far side of the
  // edge (two-side), in the face's plane.
  const double vx[3] = {0, frame.l, frame.cx}, vy[3] = {0, 0, frame.cy};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const double len = std::hypot(vx[j] - vx[i], vy[j] - vy[i]);
    const double ux = (vx[j] - vx[i]) / len, uy = (vy[j] - vy[i]) / len;
    // (-uy, ux) points into the face: it is counter-clockwise (cy > 0).
    for (int c = 0; c < 3; ++c) {
      double x, y;
      Place(len, d[i][c], d[j][c], &x, &y);
      out.image[c][i][0] = static_cast<float>(vx[i] + x * ux + y * uy);
      out.image[c][i][1] = static_cast<float>(vy[i] + x * uy - y * ux);
    }
  }
  return out;
}

LiftedPoint QueryEngine::Lift(const SurfacePoint& p) const {
  const int k = Heaviest(p);
  if (p.w[k] >= 1.0) return VertexLift(view_.faces[3 * p.face + k]);  // at a vertex: exact record
  const FaceLift& fl = face_lifts_[p.face];
  if (fl.triangle < 0) return SlowLift(p, k);
  const double px = p.w[1] * fl.l + p.w[2] * fl.cx, py = p.w[2] * fl.cy;
  LiftedPoint out;
  if (fl.approx < 0) {
    out.triangle = fl.triangle;
    for (int c = 0; c < 3; ++c) {
      out.corner[c] = fl.corner[c];
      out.distance[c] = Norm2(px - fl.src[c][0], py - fl.src[c][1]);
    }
    return out;
  }
  const ApproxLift& al = ApproxLiftOf(fl, k);
  out.triangle = al.triangle;
  for (int c = 0; c < 3; ++c) {
    out.corner[c] = al.corner[c];
    double best = kInf;
    for (int i = 0; i < 3; ++i) {
      const double dx = px - al.image[c][i][0], dy = py - al.image[c][i][1];
      best = std::min(best, dx * dx + dy * dy);
    }
    out.distance[c] = std::sqrt(best);
  }
  return out;
}

void QueryEngine::PrefetchFace(const SurfacePoint& p) const {
  __builtin_prefetch(&view_.faces[3 * p.face]);
  __builtin_prefetch(&face_lifts_[p.face]);
}

void QueryEngine::PrefetchLift(const SurfacePoint& p) const {
  const int k = Heaviest(p);
  const FaceLift& fl = face_lifts_[p.face];
  if (p.w[k] >= 1.0 || fl.triangle < 0) {
    __builtin_prefetch(&records_[view_.faces[3 * p.face + k]]);
  } else if (fl.approx >= 0) {
    const char* line = reinterpret_cast<const char*>(&ApproxLiftOf(fl, k));
    Touch(line, sizeof(ApproxLift));
  }
}

LiftedPoint QueryEngine::SlowLift(const SurfacePoint& p, int heaviest) const {
  const int32_t* f = &view_.faces[3 * p.face];
  const int32_t t0 = records_[f[0]].triangle, t1 = records_[f[1]].triangle,
                t2 = records_[f[2]].triangle;
  int k = heaviest;
  if (t0 == t1 || t0 == t2) {
    k = 0;
  } else if (t1 == t2) {
    k = 1;
  }
  LiftedPoint out = VertexLift(f[k]);
  double d[3][3];
  const bool exact = FaceDistances(f, out, d);
  const FaceFrame frame = FaceFrameOf(f);
  LiftInFace(frame.l, frame.cx, frame.cy, p.w[1] * frame.l + p.w[2] * frame.cx, p.w[2] * frame.cy,
             exact, d, &out.distance);
  return out;
}

double QueryEngine::LiftedDistance(const LiftedPoint& p0, const LiftedPoint& q0) const {
  if (p0.triangle == q0.triangle) {
    // Case 3.1: both placed in the triangle (each on the side its distances
    // say, which for points inside is the one-side unfolding).
    const Frame<double>* frames = &frames_[3 * p0.triangle];
    const Placed<double> p = PlaceInTriangle(frames, p0.distance.data());
    const Placed<double> q = PlaceInTriangle(frames, q0.distance.data());
    double best = kInf;
    for (int i = 0; i < 3; ++i) {
      const double dx = p.x[i] - q.x[i], dy = p.y[i] - q.y[i];
      best = std::min(best, dx * dx + dy * dy);
    }
    return std::sqrt(best);
  }
  // Case 3.2, in a fixed order so that the result is symmetric.
  const bool swap = p0.triangle > q0.triangle;
  const LiftedPoint& p = swap ? q0 : p0;
  const LiftedPoint& q = swap ? p0 : q0;
  // Rows of q's corners: the entries DistanceBatch prefetches.
  if (!(Matrix(q.corner[0], p.corner[0]) < kInf)) return kInf;  // different components
  return kernel::FarDistance(GatherFar(p, q));
}

kernel::FarPair QueryEngine::GatherFar(const LiftedPoint& p, const LiftedPoint& q) const {
  kernel::FarPair pair;
  pair.p_frames = &frames_[3 * p.triangle];
  pair.q_frames = &frames_[3 * q.triangle];
  pair.p_distance = p.distance.data();
  pair.q_distance = q.distance.data();
  for (int j = 0; j < 3; ++j) {
    const int32_t s = q.corner[j];
    pair.shared[j] = -1;
    for (int i = 0; i < 3; ++i) {
      pair.e[j][i] = Matrix(s, p.corner[i]);
      if (p.corner[i] == s) pair.shared[j] = p.distance[i];  // case 2.1
    }
  }
  return pair;
}

void QueryEngine::LiftedDistanceLanes(const LiftedPoint* a, const LiftedPoint* b,
                                      double* out) const {
  // Each lane in the order of LiftedDistance's case 3.2; the other cases
  // (same triangle, different components) are answered one at a time.
  constexpr int W = kernel::kLanes;
  kernel::FarPair pairs[W];
  bool far[W];
  for (int k = 0; k < W; ++k) {
    const bool swap = a[k].triangle > b[k].triangle;
    const LiftedPoint& p = swap ? b[k] : a[k];
    const LiftedPoint& q = swap ? a[k] : b[k];
    far[k] = p.triangle != q.triangle && Matrix(q.corner[0], p.corner[0]) < kInf;
    pairs[k] = GatherFar(p, q);
  }
  if (options_.vector_lanes) {
    kernel::FarDistances(pairs, out);
  } else {
    kernel::FarDistancesOneByOne(pairs, out);
  }
  for (int k = 0; k < W; ++k) {
    if (!far[k]) out[k] = LiftedDistance(a[k], b[k]);
  }
}

double QueryEngine::DistanceUnchecked(const SurfacePoint& p, const SurfacePoint& q) const {
  const LiftedPoint a = Lift(p), b = Lift(q);
  const double d = LiftedDistance(a, b);
  return AreNear(a, b) ? AtLeastChord(p, q, d) : d;
}

bool QueryEngine::AreNear(const LiftedPoint& a, const LiftedPoint& b) const {
  if (a.triangle == b.triangle) return true;
  for (int i = 0; i < 3; ++i) {
    if (triangles_[a.triangle].neighbor[i] == b.triangle) return true;
  }
  return false;
}

bool QueryEngine::IsNearPair(const SurfacePoint& p, const SurfacePoint& q) const {
  return AreNear(Lift(Canonical(p)), Lift(Canonical(q)));
}

mesh::Vec3 QueryEngine::PositionOf(const SurfacePoint& p) const {
  const int32_t* f = &view_.faces[3 * p.face];
  return p.w[0] * view_.Position(f[0]) + p.w[1] * view_.Position(f[1]) +
         p.w[2] * view_.Position(f[2]);
}

double QueryEngine::AtLeastChord(const SurfacePoint& p, const SurfacePoint& q, double d) const {
  return std::max(d, (PositionOf(p) - PositionOf(q)).norm());
}

double QueryEngine::LiftedSpread(const LiftedPoint& p, const LiftedPoint& q,
                                 std::optional<double> unfolded) const {
  if (p.triangle == q.triangle || !(Matrix(q.corner[0], p.corner[0]) < kInf)) return 0;
  // LiftedDistance takes the point in the triangle of smaller id first.
  const bool swap = p.triangle > q.triangle;
  const LiftedPoint& lo = swap ? q : p;
  const LiftedPoint& hi = swap ? p : q;
  const double canonical = unfolded ? *unfolded : kernel::FarDistance(GatherFar(lo, hi));
  return std::abs(canonical - kernel::FarDistance(GatherFar(hi, lo)));
}

double QueryEngine::UnfoldingSpread(const SurfacePoint& p, const SurfacePoint& q) const {
  return LiftedSpread(Lift(Canonical(p)), Lift(Canonical(q)));
}

double QueryEngine::BoundOf(AnswerKind kind, bool vertex_pair, double d, double spread) const {
  const index::AccuracyRecord* accuracy = index_->accuracy();
  if (accuracy == nullptr) return std::numeric_limits<double>::quiet_NaN();
  if (kind == AnswerKind::kExact || !(d < kInf)) return 0;
  const double x = d / accuracy->scale_length;
  int b = 0;
  while (b + 1 < index::kAccuracyBins && x >= index::kAccuracyBinUpper[b]) ++b;
  const int k = vertex_pair ? 0 : 1;
  switch (kind) {
    case AnswerKind::kUnfold:
      if (const index::SpreadBoundRecord* s = index_->spread_bounds(); s != nullptr) {
        return s->factor[k][b] * (spread + s->epsilon[k][b] * d);
      }
      return accuracy->unfold_bound[k][b];
    case AnswerKind::kTrace:
      return accuracy->trace_bound[vertex_pair ? 2 : 0][b];
    case AnswerKind::kWrappedTrace:
      return accuracy->trace_bound[vertex_pair ? 3 : 1][b];
    case AnswerKind::kExact:
      break;
  }
  return 0;
}

double QueryEngine::Refine(const SurfacePoint& p_in, const SurfacePoint& q_in,
                           const LiftedPoint& lp, const LiftedPoint& lq, double unfolded, bool near,
                           const DistanceOptions& options, QueryScratch* scratch,
                           double* bound) const {
  const SurfacePoint p = InLowestFaceIfVertex(p_in), q = InLowestFaceIfVertex(q_in);
  if (!(unfolded < kInf)) {  // different components: exactly unreachable
    if (bound != nullptr) *bound = BoundOf(AnswerKind::kExact, false, unfolded);
    return unfolded;
  }
  // The refinements work from one point to the other: from the smaller, so
  // that the answer is symmetric.
  const bool swap = std::tie(q.face, q.w) < std::tie(p.face, p.w);
  const SurfacePoint& from = swap ? q : p;
  const SurfacePoint& to = swap ? p : q;
  auto at_vertex = [](const SurfacePoint& x) { return x.w[0] == 1 || x.w[1] == 1 || x.w[2] == 1; };
  const bool vertex_pair = at_vertex(p) && at_vertex(q);
  double d = near ? AtLeastChord(p, q, unfolded) : unfolded;
  AnswerKind kind = AnswerKind::kUnfold;
  // The bound of an answer; the spread of an O(1) answer is computed once,
  // when first needed.
  std::optional<double> spread;
  auto bound_of = [&](AnswerKind k, double at) {
    if (k == AnswerKind::kUnfold && !spread) {
      spread = index_->spread_bounds() != nullptr ? LiftedSpread(lp, lq, unfolded) : 0;
    }
    return BoundOf(k, vertex_pair, at, spread.value_or(0));
  };
  auto trace = [&] {
    // The O(1) answer plus its bound: a straight walk longer than that is
    // doubted (NaN without calibration: none is).
    const double plausible = unfolded + bound_of(AnswerKind::kUnfold, unfolded);
    const std::optional<Trace> t =
        PathNearDistance(from, to, std::isnan(plausible) ? kInf : plausible);
    if (!t) return false;
    d = t->length;
    kind = t->wraps ? AnswerKind::kWrappedTrace : AnswerKind::kTrace;
    return true;
  };
  auto exact = [&] {
    const std::optional<double> e = ExactNearDistance(from, to, scratch);
    if (!e) return false;
    d = *e;
    kind = AnswerKind::kExact;
    return true;
  };
  // A trace is a surface path, never shorter than the geodesic; one longer
  // than the O(1) answer plus that answer's bound has settled in a wrong
  // corridor (round the wrong side of a feature). Under a tolerance it is
  // answered exactly; by default it stays (an exact propagation per such
  // pair halved the default mode's throughput for little gain:
  // tests/bench/README.md). Needs the calibration (else the bound is NaN and
  // no trace is doubted).
  auto wrong_corridor = [&] {
    return (kind == AnswerKind::kTrace || kind == AnswerKind::kWrappedTrace) &&
           d > unfolded + bound_of(AnswerKind::kUnfold, unfolded);
  };
  if (near || unfolded < refine_below_) {
    switch (options.near_pairs) {
      case NearPairs::kPath:
        trace();
        break;
      case NearPairs::kExact:
        exact();
        break;
      case NearPairs::kUnfold:
        break;
    }
  }
  if (options.tolerance > 0) {
    auto within = [&] { return bound_of(kind, d) <= options.tolerance * d; };
    if (kind == AnswerKind::kUnfold && !within() && !trace()) exact();
    if (kind != AnswerKind::kExact && (!within() || wrong_corridor())) exact();
  }
  if (bound != nullptr) *bound = bound_of(kind, d);
  return d;
}

absl::StatusOr<double> QueryEngine::TracedDistance(const SurfacePoint& p, const SurfacePoint& q,
                                                   bool* wraps) const {
  GEODEX_RETURN_IF_ERROR(Validate(p));
  GEODEX_RETURN_IF_ERROR(Validate(q));
  const SurfacePoint a = InLowestFaceIfVertex(Canonical(p)), b = InLowestFaceIfVertex(Canonical(q));
  const bool swap = std::tie(b.face, b.w) < std::tie(a.face, a.w);
  const std::optional<Trace> t = PathNearDistance(swap ? b : a, swap ? a : b);
  if (!t) return absl::NotFoundError("no trace between the points");
  if (wraps != nullptr) *wraps = t->wraps;
  return t->length;
}

absl::Status QueryEngine::CheckOptions(const DistanceOptions& options, bool bounds) const {
  if (!(options.tolerance >= 0) || !std::isfinite(options.tolerance)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tolerance must be finite and >= 0, not %g", options.tolerance));
  }
  if ((bounds || options.tolerance > 0) && index_->accuracy() == nullptr) {
    return absl::FailedPreconditionError(
        "the index has no accuracy calibration (error bounds, tolerance): rebuild it, or add one "
        "with geodex-build calibrate");
  }
  return absl::OkStatus();
}

bool QueryEngine::NeedsRefine(const DistanceOptions& options, bool bounds, bool near,
                              double unfolded) const {
  return near || bounds || options.tolerance > 0 ||
         (options.near_pairs != NearPairs::kUnfold && unfolded < refine_below_);
}

absl::StatusOr<double> QueryEngine::Distance(const SurfacePoint& p, const SurfacePoint& q,
                                             const DistanceOptions& options, QueryScratch* scratch,
                                             double* bound) const {
  GEODEX_RETURN_IF_ERROR(Validate(p));
  GEODEX_RETURN_IF_ERROR(Validate(q));
  GEODEX_RETURN_IF_ERROR(CheckOptions(options, bound != nullptr));
  const SurfacePoint a = Canonical(p), b = Canonical(q);
  const LiftedPoint la = Lift(a), lb = Lift(b);
  const double d = LiftedDistance(la, lb);
  const bool near = AreNear(la, lb);
  if (!NeedsRefine(options, bound != nullptr, near, d)) return d;
  return Refine(a, b, la, lb, d, near, options, scratch, bound);
}

absl::Status QueryEngine::DistanceBatch(std::span<const SurfacePoint> a,
                                        std::span<const SurfacePoint> b, std::span<double> out,
                                        const DistanceOptions& options, QueryScratch* scratch,
                                        std::span<double> bounds) const {
  if (a.size() != b.size() || a.size() != out.size() ||
      (!bounds.empty() && bounds.size() != out.size())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("batch arrays differ in length (%d, %d, %d, bounds %d)", a.size(), b.size(),
                        out.size(), bounds.size()));
  }
  const bool want_bounds = !bounds.empty();
  GEODEX_RETURN_IF_ERROR(CheckOptions(options, want_bounds));
  auto refine = [&](size_t k, const LiftedPoint& p, const LiftedPoint& q) {
    const bool near = AreNear(p, q);
    if (NeedsRefine(options, want_bounds, near, out[k])) {
      out[k] = Refine(Canonical(a[k]), Canonical(b[k]), p, q, out[k], near, options, scratch,
                      want_bounds ? &bounds[k] : nullptr);
    }
  };
  for (size_t i = 0; i < a.size(); ++i) {
    for (const SurfacePoint* p : {&a[i], &b[i]}) {
      const absl::Status status = Validate(*p);
      if (!status.ok()) {
        return absl::Status(
            status.code(),
            absl::StrFormat("pair %d, point %c: %s", i, p == &a[i] ? 'A' : 'B', status.message()));
      }
    }
  }
  const size_t n = a.size();
  // A query's loads depend on each other (face -> face lift -> approximate
  // lift or vertex record -> geodesic triangles -> sample matrix), so the
  // batch runs as a software pipeline: the faces 16 pairs ahead are
  // prefetched, what their lifts read next is brought in 12 ahead (see
  // PrefetchLift), the points 8 ahead are
  // lifted (and the frames and matrix entries their distance will read are
  // prefetched), and the distances are computed from the lifts, kLanes pairs
  // per instruction.
  constexpr size_t kFaceAhead = 16, kLiftDataAhead = 12, kLiftAhead = 8, kRing = 16;
  constexpr size_t W = kernel::kLanes;
  static_assert(kLiftAhead % W == 0 && kRing % W == 0 && kRing >= kLiftAhead + W);
  LiftedPoint lift_a[kRing], lift_b[kRing];
  auto lift = [&](size_t j) {
    LiftedPoint& p = lift_a[j % kRing];
    LiftedPoint& q = lift_b[j % kRing];
    p = Lift(Canonical(a[j]));
    q = Lift(Canonical(b[j]));
    __builtin_prefetch(&frames_[3 * p.triangle]);
    __builtin_prefetch(&frames_[3 * q.triangle]);
    // The entries LiftedDistance reads: rows of the corners of the point in
    // the triangle of larger id, columns of the other's.
    const LiftedPoint& lo = p.triangle > q.triangle ? q : p;
    const LiftedPoint& hi = p.triangle > q.triangle ? p : q;
    for (int r = 0; r < 3; ++r) {
      const float* row = &matrix_[static_cast<size_t>(hi.corner[r]) * num_samples_];
      for (int c = 0; c < 3; ++c) __builtin_prefetch(row + lo.corner[c]);
    }
  };
  for (size_t j = 0; j < std::min(n, kLiftAhead); ++j) lift(j);
  size_t i = 0;
  for (; i + W <= n; i += W) {
    for (size_t k = i; k < i + W; ++k) {
      if (k + kFaceAhead < n) {
        PrefetchFace(a[k + kFaceAhead]);
        PrefetchFace(b[k + kFaceAhead]);
      }
      if (k + kLiftDataAhead < n) {
        PrefetchLift(a[k + kLiftDataAhead]);
        PrefetchLift(b[k + kLiftDataAhead]);
      }
    }
    LiftedDistanceLanes(&lift_a[i % kRing], &lift_b[i % kRing], &out[i]);
    for (size_t k = i; k < i + W; ++k) {
      refine(k, lift_a[k % kRing], lift_b[k % kRing]);
      if (k + kLiftAhead < n) lift(k + kLiftAhead);
    }
  }
  for (; i < n; ++i) {
    const LiftedPoint& p = lift_a[i % kRing];
    const LiftedPoint& q = lift_b[i % kRing];
    out[i] = LiftedDistance(p, q);
    refine(i, p, q);
  }
  return absl::OkStatus();
}

double QueryEngine::LinearInterpolationDistance(const SurfacePoint& p0,
                                                const SurfacePoint& q0) const {
  const LiftedPoint p = Lift(Canonical(p0)), q = Lift(Canonical(q0));
  if (!(Matrix(p.corner[0], q.corner[0]) < kInf)) return kInf;
  auto lambda = [&](const LiftedPoint& x) {
    return geometry::UnfoldedBarycentric(Matrix(x.corner[0], x.corner[1]),
                                         Matrix(x.corner[1], x.corner[2]),
                                         Matrix(x.corner[2], x.corner[0]), x.distance);
  };
  const auto lp = lambda(p), lq = lambda(q);
  double d = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) d += lp[i] * Matrix(p.corner[i], q.corner[j]) * lq[j];
  }
  return d;
}

absl::StatusOr<DistanceField> QueryEngine::Field(std::span<const SurfacePoint> sources) const {
  if (sources.empty()) return absl::InvalidArgumentError("no sources given");
  std::vector<LiftedPoint> lifted;
  std::vector<mesh::Vec3> at;
  for (size_t s = 0; s < sources.size(); ++s) {
    const absl::Status status = Validate(sources[s]);
    if (!status.ok()) {
      return absl::Status(status.code(), absl::StrFormat("source %d: %s", s, status.message()));
    }
    const SurfacePoint source = Canonical(sources[s]);
    lifted.push_back(Lift(source));
    at.push_back(PositionOf(source));
  }
  DistanceField field;
  const int32_t n = index_->num_vertices();
  field.distance.assign(n, kInf);
  field.nearest.assign(n, -1);
  for (int32_t v = 0; v < n; ++v) {
    const index::VertexRecord& r = records_[v];
    if (r.triangle < 0) continue;
    LiftedPoint x;
    x.triangle = r.triangle;
    for (int c = 0; c < 3; ++c) {
      x.corner[c] = r.corner[c];
      x.distance[c] = r.distance[c];
    }
    for (size_t s = 0; s < lifted.size(); ++s) {
      double d = LiftedDistance(lifted[s], x);
      if (AreNear(lifted[s], x))
        d = std::max(d, (at[s] - view_.Position(v)).norm());  // AtLeastChord
      if (d < field.distance[v]) {
        field.distance[v] = d;
        field.nearest[v] = static_cast<int32_t>(s);
      }
    }
  }
  return field;
}

absl::StatusOr<LocatedPoint> QueryEngine::Locate(const mesh::Vec3& x) const {
  return locator_.Locate(x);
}

}  // namespace geodex::query
