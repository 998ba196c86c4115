#include "core/query/query_engine.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::query {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Paper §5.1. Places a point at distances (da, db) from the ends of an edge of
// length l lying on the x axis: x along the edge, y >= 0 its height. Distances
// that break the triangle inequality (numerically, or because geodesic
// triangles are curved) are clamped onto the edge instead of giving NaN.
inline void Place(double l, double da, double db, double* x, double* y) {
  *x = (l * l + da * da - db * db) / (2 * l);
  *y = std::sqrt(std::max(da * da - *x * *x, 0.0));
}

// Squared distance of the images of p and q, p at (pa, pb) and q at (qa, qb)
// from the ends of an edge of length l, on opposite sides of it (two-side
// unfolding).
inline double TwoSide2(double l, double pa, double pb, double qa, double qb) {
  if (!(l > 0)) return (pa + qa) * (pa + qa);
  double xp, yp, xq, yq;
  Place(l, pa, pb, &xp, &yp);
  Place(l, qa, qb, &xq, &yq);
  const double dx = xp - xq, dy = yp + yq;
  return dx * dx + dy * dy;
}


// Places a point at distances (da, db) from the edge's ends and dc from the
// third corner: like Place, on the side of the edge whose mirror image
// matches dc better. Points beyond an edge of the triangle (common near mesh
// boundaries and for far samples) thus land outside it, where one-side and
// two-side unfolding would put them inside or on the wrong side.
inline void PlaceSigned(const EdgeFrame& e, double da, double db, double dc, double* x, double* y) {
  if (!(e.l > 0)) {
    *x = 0;
    *y = da;
    return;
  }
  Place(e.l, da, db, x, y);
  // Squared distances to the third corner from (x, +y) and (x, -y) differ by
  // 4 y cy; pick the side whose value is nearer dc^2.
  const double dx = *x - e.cx;
  if (dc * dc > dx * dx + *y * *y + e.cy * e.cy) *y = -*y;
}

// Barycentric coordinates of the point at distances d from the corners of the
// planar triangle with side lengths (ab, bc, ca), on the side that best
// matches d[2] (used by the linear-interpolation baseline).
std::array<double, 3> Barycentric(double ab, double bc, double ca, const std::array<double, 3>& d) {
  if (!(ab > 0)) return {1, 0, 0};
  double cx, cy, px, py;
  Place(ab, ca, bc, &cx, &cy);
  Place(ab, d[0], d[1], &px, &py);
  if (std::abs(std::hypot(px - cx, -py - cy) - d[2]) < std::abs(std::hypot(px - cx, py - cy) - d[2])) {
    py = -py;
  }
  const double area = ab * cy;
  if (!(area > 0)) return {1, 0, 0};
  const double lc = py / cy;
  const double lb = (px * cy - py * cx) / area;
  return {1 - lb - lc, lb, lc};
}

}  // namespace

absl::StatusOr<std::shared_ptr<const QueryEngine>> QueryEngine::Create(
    std::shared_ptr<const index::Index> index, QueryOptions options) {
  if (index == nullptr) return absl::InvalidArgumentError("no index");
  if (index->num_triangles() == 0 || index->num_samples() == 0) {
    return absl::FailedPreconditionError("the index has no geodesic triangles");
  }
  std::shared_ptr<QueryEngine> engine(new QueryEngine(std::move(index), options));
  if (options.exact_near_pairs) {
    const index::Index& ix = *engine->index_;
    std::vector<mesh::Vec3> positions(ix.num_vertices());
    for (int32_t v = 0; v < ix.num_vertices(); ++v) positions[v] = engine->Position(v);
    std::vector<mesh::Triangle> faces(ix.num_faces());
    for (int32_t f = 0; f < ix.num_faces(); ++f) {
      faces[f] = {ix.faces()[3 * f], ix.faces()[3 * f + 1], ix.faces()[3 * f + 2]};
    }
    GEODEX_ASSIGN_OR_RETURN(mesh::Mesh m, mesh::Mesh::Create(std::move(positions), std::move(faces), "index"));
    engine->mesh_ = std::make_unique<mesh::Mesh>(std::move(m));
  }
  return std::shared_ptr<const QueryEngine>(std::move(engine));
}

QueryEngine::QueryEngine(std::shared_ptr<const index::Index> index, QueryOptions options)
    : index_(std::move(index)),
      options_(options),
      positions_(index_->positions()),
      faces_(index_->faces()),
      twins_(index_->twins()),
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
      EdgeFrame& e = frames_[3 * t + i];
      e.l = Matrix(a, b);
      if (e.l > 0) {
        Place(e.l, Matrix(a, o), Matrix(b, o), &e.cx, &e.cy);
      } else {
        e.cx = e.cy = 0;
      }
    }
  }
}

absl::Status QueryEngine::Validate(const SurfacePoint& p) const {
  if (p.face < 0 || p.face >= index_->num_faces()) {
    return absl::OutOfRangeError(
        absl::StrFormat("face id %d out of range [0, %d)", p.face, index_->num_faces()));
  }
  const double tol = options_.weight_tolerance;
  double sum = 0;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(p.w[i])) {
      return absl::InvalidArgumentError(
          absl::StrFormat("barycentric weight %d of face %d is not finite", i, p.face));
    }
    if (p.w[i] < -tol) {
      return absl::InvalidArgumentError(
          absl::StrFormat("barycentric weight %d of face %d is negative (%g)", i, p.face, p.w[i]));
    }
    sum += p.w[i];
  }
  if (std::abs(sum - 1) > tol) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "barycentric weights of face %d sum to %.17g, not 1 (tolerance %g)", p.face, sum, tol));
  }
  return absl::OkStatus();
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
    const int32_t g = twins_[h];
    if (g >= 0 && g / 3 < c.face) {
      SurfacePoint t{g / 3, {0, 0, 0}};
      t.w[g % 3] = c.w[(zero + 2) % 3];        // Origin(g) = Dest(h)
      t.w[(g % 3 + 1) % 3] = c.w[(zero + 1) % 3];  // Dest(g) = Origin(h)
      return t;
    }
  }
  return c;
}

double QueryEngine::VertexToSample(int32_t v, int32_t s) const {
  const index::VertexRecord& r = records_[v];
  LiftedPoint p;
  p.triangle = r.triangle;
  for (int i = 0; i < 3; ++i) {
    p.corner[i] = r.corner[i];
    p.distance[i] = r.distance[i];
  }
  return ToSample(p, s);
}

double QueryEngine::ToSample(const LiftedPoint& p, int32_t s) const {
  for (int i = 0; i < 3; ++i) {
    if (p.corner[i] == s) return p.distance[i];  // paper §5.2, case 2.1
  }
  // Case 2.2: unfold the sample and the point about each edge of the point's
  // triangle, each on the side its distances say.
  const double to_corner[3] = {Matrix(s, p.corner[0]), Matrix(s, p.corner[1]),
                               Matrix(s, p.corner[2])};
  return std::sqrt(UnfoldedDistance2(p.triangle, p.distance.data(), to_corner));
}

double QueryEngine::UnfoldedDistance2(int32_t triangle, const double* p, const double* q) const {
  const EdgeFrame* frames = &frames_[3 * triangle];
  double best = kInf;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    double xp, yp, xq, yq;
    PlaceSigned(frames[i], p[i], p[j], p[k], &xp, &yp);
    PlaceSigned(frames[i], q[i], q[j], q[k], &xq, &yq);
    const double dx = xp - xq, dy = yp - yq;
    best = std::min(best, dx * dx + dy * dy);
  }
  return best;
}

LiftedPoint QueryEngine::Lift(const SurfacePoint& p) const {
  const int32_t* f = &faces_[3 * p.face];
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (p.w[i] > p.w[k]) k = i;
  }
  const index::VertexRecord& anchor = records_[f[k]];
  LiftedPoint out;
  out.triangle = anchor.triangle;
  for (int c = 0; c < 3; ++c) {
    out.corner[c] = anchor.corner[c];
    out.distance[c] = anchor.distance[c];
  }
  if (p.w[k] >= 1.0) return out;  // at a vertex: its record is exact

  // Distances from the face's vertices to the corners of the anchor's triangle.
  double d[3][3];
  for (int i = 0; i < 3; ++i) {
    const index::VertexRecord& r = records_[f[i]];
    for (int c = 0; c < 3; ++c) {
      d[i][c] = r.triangle == out.triangle ? r.distance[c] : VertexToSample(f[i], out.corner[c]);
    }
  }
  // Paper §5.2, case 4: unfold the face about each of its edges.
  const mesh::Vec3 v[3] = {Position(f[0]), Position(f[1]), Position(f[2])};
  const mesh::Vec3 x = p.w[0] * v[0] + p.w[1] * v[1] + p.w[2] * v[2];
  const double to_vertex[3] = {(x - v[0]).norm(), (x - v[1]).norm(), (x - v[2]).norm()};
  const double edge[3] = {(v[1] - v[0]).norm(), (v[2] - v[1]).norm(), (v[0] - v[2]).norm()};
  for (int c = 0; c < 3; ++c) {
    double best = kInf;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      best = std::min(best, TwoSide2(edge[i], to_vertex[i], to_vertex[j], d[i][c], d[j][c]));
    }
    out.distance[c] = std::sqrt(best);
  }
  return out;
}

double QueryEngine::LiftedDistance(const LiftedPoint& p0, const LiftedPoint& q0) const {
  if (!(Matrix(p0.corner[0], q0.corner[0]) < kInf)) return kInf;  // different components
  if (p0.triangle == q0.triangle) {  // case 3.1
    return std::sqrt(UnfoldedDistance2(p0.triangle, p0.distance.data(), q0.distance.data()));
  }
  // Case 3.2, in a fixed order so that the result is symmetric.
  const bool swap = p0.triangle > q0.triangle;
  const LiftedPoint& p = swap ? q0 : p0;
  const LiftedPoint& q = swap ? p0 : q0;
  const double to_corner[3] = {ToSample(p, q.corner[0]), ToSample(p, q.corner[1]),
                               ToSample(p, q.corner[2])};
  return std::sqrt(UnfoldedDistance2(q.triangle, to_corner, q.distance.data()));
}

double QueryEngine::DistanceUnchecked(const SurfacePoint& p, const SurfacePoint& q) const {
  return LiftedDistance(Lift(p), Lift(q));
}

bool QueryEngine::IsNearPair(const SurfacePoint& p, const SurfacePoint& q) const {
  const LiftedPoint a = Lift(Canonical(p)), b = Lift(Canonical(q));
  if (a.triangle == b.triangle) return true;
  for (int i = 0; i < 3; ++i) {
    if (triangles_[a.triangle].neighbor[i] == b.triangle) return true;
  }
  return false;
}

double QueryEngine::ExactNearDistance(const SurfacePoint& p, const SurfacePoint& q,
                                      QueryScratch* scratch) const {
  if (scratch->solver_ == nullptr || scratch->mesh_ != mesh_.get()) {
    scratch->solver_ = std::make_unique<geodesic::ExactGeodesicSolver>(*mesh_);
    scratch->mesh_ = mesh_.get();
  }
  // Propagate from the smaller point so the answer is symmetric.
  const bool swap = std::tie(q.face, q.w) < std::tie(p.face, p.w);
  const SurfacePoint& from = swap ? q : p;
  const SurfacePoint& to = swap ? p : q;
  geodesic::GeodesicOptions options;
  options.stop_points = {to};
  if (!scratch->solver_->Propagate({from}, options).ok()) return DistanceUnchecked(p, q);
  return scratch->solver_->DistanceAt(to);
}

absl::StatusOr<double> QueryEngine::Distance(const SurfacePoint& p, const SurfacePoint& q,
                                             QueryScratch* scratch) const {
  GEODEX_RETURN_IF_ERROR(Validate(p));
  GEODEX_RETURN_IF_ERROR(Validate(q));
  const SurfacePoint a = Canonical(p), b = Canonical(q);
  if (options_.exact_near_pairs && scratch != nullptr && IsNearPair(a, b)) {
    return ExactNearDistance(a, b, scratch);
  }
  return DistanceUnchecked(a, b);
}

absl::Status QueryEngine::DistanceBatch(std::span<const SurfacePoint> a,
                                        std::span<const SurfacePoint> b, std::span<double> out,
                                        QueryScratch* scratch) const {
  if (a.size() != b.size() || a.size() != out.size()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "batch arrays differ in length (%d, %d, %d)", a.size(), b.size(), out.size()));
  }
  for (size_t i = 0; i < a.size(); ++i) {
    for (const SurfacePoint* p : {&a[i], &b[i]}) {
      const absl::Status status = Validate(*p);
      if (!status.ok()) {
        return absl::Status(status.code(), absl::StrFormat("pair %d, point %c: %s", i,
                                                           p == &a[i] ? 'A' : 'B', status.message()));
      }
    }
  }
  const bool exact = options_.exact_near_pairs && scratch != nullptr;
  for (size_t i = 0; i < a.size(); ++i) {
    const SurfacePoint p = Canonical(a[i]), q = Canonical(b[i]);
    out[i] = exact && IsNearPair(p, q) ? ExactNearDistance(p, q, scratch) : DistanceUnchecked(p, q);
  }
  return absl::OkStatus();
}

double QueryEngine::LinearInterpolationDistance(const SurfacePoint& p0,
                                                const SurfacePoint& q0) const {
  const LiftedPoint p = Lift(Canonical(p0)), q = Lift(Canonical(q0));
  if (!(Matrix(p.corner[0], q.corner[0]) < kInf)) return kInf;
  auto lambda = [&](const LiftedPoint& x) {
    return Barycentric(Matrix(x.corner[0], x.corner[1]), Matrix(x.corner[1], x.corner[2]),
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
  for (size_t s = 0; s < sources.size(); ++s) {
    const absl::Status status = Validate(sources[s]);
    if (!status.ok()) {
      return absl::Status(status.code(), absl::StrFormat("source %d: %s", s, status.message()));
    }
    lifted.push_back(Lift(Canonical(sources[s])));
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
      const double d = LiftedDistance(lifted[s], x);
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
