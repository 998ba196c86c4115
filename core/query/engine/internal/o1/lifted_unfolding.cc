#include "core/query/engine/internal/o1/lifted_unfolding.h"

#include <cmath>
#include <limits>

#include "core/geometry/planar_unfolding.h"

namespace geodex::query {
namespace {

using kernel::Frame;
using kernel::Placed;
using kernel::PlaceInTriangle;
using kernel::TwoSideToOutside2;

}  // namespace

LiftedUnfolding::LiftedUnfolding(const index::Index& index, bool vector_lanes)
    : matrix_(index.matrix()),
      triangles_(index.triangles()),
      vector_lanes_(vector_lanes) {
  frames_.resize(3 * triangles_.size());
  for (size_t t = 0; t < triangles_.size(); ++t) {
    const int32_t* c = triangles_[t].corner;
    for (int i = 0; i < 3; ++i) {
      const int32_t a = c[i], b = c[(i + 1) % 3], o = c[(i + 2) % 3];
      Frame<double>& e = frames_[3 * t + i];
      e.l = Matrix(a, b);
      if (e.l > 0) {
        geometry::Place(e.l, Matrix(a, o), Matrix(b, o), &e.cx, &e.cy);
        e.inv_2l = 1 / (2 * e.l);
      } else {
        e.cx = e.cy = e.inv_2l = 0;
      }
    }
  }
}

double LiftedUnfolding::ToSample(const LiftedPoint& p, int32_t s) const {
  for (int i = 0; i < 3; ++i) {
    if (p.corner[i] == s) return p.distance[i];  // paper §5.2, case 2.1
  }
  const Frame<double>* frames = Frames(p.triangle);
  const double e[3] = {Matrix(s, p.corner[0]), Matrix(s, p.corner[1]), Matrix(s, p.corner[2])};
  return std::sqrt(TwoSideToOutside2(frames, PlaceInTriangle(frames, p.distance.data()), e));
}

void LiftedUnfolding::DistanceLanes(const LiftedPoint* a, const LiftedPoint* b, double* out) const {
  // Each lane in the order of Distance's case 3.2; the other cases (same
  // triangle, different components) are answered one at a time.
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
  if (vector_lanes_) {
    kernel::FarDistances(pairs, out);
  } else {
    kernel::FarDistancesOneByOne(pairs, out);
  }
  for (int k = 0; k < W; ++k) {
    if (!far[k]) out[k] = Distance(a[k], b[k]);
  }
}

double LiftedUnfolding::Spread(const LiftedPoint& p, const LiftedPoint& q,
                               std::optional<double> unfolded) const {
  if (p.triangle == q.triangle || !(Matrix(q.corner[0], p.corner[0]) < kInf)) return 0;
  // Distance takes the point in the triangle of smaller id first.
  const bool swap = p.triangle > q.triangle;
  const LiftedPoint& lo = swap ? q : p;
  const LiftedPoint& hi = swap ? p : q;
  const double canonical = unfolded ? *unfolded : kernel::FarDistance(GatherFar(lo, hi));
  return std::abs(canonical - kernel::FarDistance(GatherFar(hi, lo)));
}

void LiftedUnfolding::Prefetch(const LiftedPoint& p, const LiftedPoint& q) const {
  __builtin_prefetch(Frames(p.triangle));
  __builtin_prefetch(Frames(q.triangle));
  // The entries Distance reads: rows of the corners of the point in the
  // triangle of larger id, columns of the other's.
  const LiftedPoint& lo = p.triangle > q.triangle ? q : p;
  const LiftedPoint& hi = p.triangle > q.triangle ? p : q;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) __builtin_prefetch(matrix_.Address(hi.corner[r], lo.corner[c]));
  }
}

double LiftedUnfolding::LinearInterpolation(const LiftedPoint& p, const LiftedPoint& q) const {
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

}  // namespace geodex::query
