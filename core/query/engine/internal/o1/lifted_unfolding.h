#pragma once

// The unfolding of lifted points (Xin, Ying & He 2012, §5.2): the O(1)
// distance between two points that each know their geodesic triangle and
// their distances to its three corner samples (lifting.h), from those
// distances and the sample distance matrix alone.
//
//  - Same triangle (case 3.1): both placed in the triangle's plane, one-side.
//  - Otherwise (case 3.2): p's distances to q's corners by two-side
//    unfolding across each edge of p's triangle (case 2.2), then q from
//    those. Computed in a fixed order (the point in the triangle of smaller
//    id first) so that the answer is symmetric.
//
// The per-edge frames of every geodesic triangle (its corners placed in the
// plane) are derived once, at load.
//
// Thread safety: immutable after construction; every method is const and
// thread-safe.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "core/index/index.h"
#include "core/query/engine/internal/o1/unfold_kernel.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

// A point lifted into a geodesic triangle (lifting.h): the triangle, its
// corner samples and the point's distances to them.
struct LiftedPoint {
  int32_t triangle = -1;
  std::array<int32_t, 3> corner = {-1, -1, -1};
  std::array<double, 3> distance = {0, 0, 0};
};

class LiftedUnfolding {
 public:
  // Over `index`'s matrix and triangles, which must outlive this object.
  // `vector_lanes`: DistanceLanes uses the AVX2 kernel when the CPU has it
  // (the answers are the same to the bit either way).
  LiftedUnfolding(const index::Index& index, bool vector_lanes);

  // The geodesic distance between samples a and b, as the index stores it.
  double Matrix(int32_t a, int32_t b) const { return matrix_(a, b); }
  // Geodesic triangle t: its corner samples and neighbours.
  const index::GeodesicTriangle& Triangle(int32_t t) const { return triangles_[t]; }
  // The frames of triangle t's three edges.
  const kernel::Frame<double>* Frames(int32_t t) const { return &frames_[3 * t]; }

  // The O(1) distance between lifted points (case 3.1 or 3.2); +inf between
  // components.
  double Distance(const LiftedPoint& p, const LiftedPoint& q) const;
  // out[k] = Distance(a[k], b[k]) for kernel::kLanes pairs, the far ones
  // computed together.
  void DistanceLanes(const LiftedPoint* a, const LiftedPoint* b, double* out) const;
  // The approximate distance from a lifted point to sample `s` (case 2.1:
  // one of its corners; else case 2.2).
  double ToSample(const LiftedPoint& p, int32_t s) const;
  // |d_pq - d_qp|: Distance's order of case 3.2 against the other one. It
  // flags the pairs whose answer errs most (error_bounds.h). 0 for points in
  // one triangle or in different components. `unfolded`, when given, is
  // Distance(p, q).
  double Spread(const LiftedPoint& p, const LiftedPoint& q,
                std::optional<double> unfolded = std::nullopt) const;
  // True when the lifts share a geodesic triangle or are in adjacent ones.
  bool AreNear(const LiftedPoint& a, const LiftedPoint& b) const;
  // Prefetches what Distance(p, q) will read: the frames and the matrix
  // entries (rows of the corners of the point in the triangle of larger id).
  void Prefetch(const LiftedPoint& p, const LiftedPoint& q) const;
  // The paper's linear-interpolation baseline (§6.3), for comparisons.
  double LinearInterpolation(const LiftedPoint& p, const LiftedPoint& q) const;

 private:
  // What case 3.2 reads for a pair, p in the triangle of smaller id.
  kernel::FarPair GatherFar(const LiftedPoint& p, const LiftedPoint& q) const;
  index::SampleMatrix matrix_;
  std::span<const index::GeodesicTriangle> triangles_;
  bool vector_lanes_ = true;
  std::vector<kernel::Frame<double>> frames_;  // 3 per geodesic triangle
};

// Inline: on the path of every query.

inline double LiftedUnfolding::Distance(const LiftedPoint& p0, const LiftedPoint& q0) const {
  if (p0.triangle == q0.triangle) {
    // Case 3.1: both placed in the triangle (each on the side its distances
    // say, which for points inside is the one-side unfolding).
    const kernel::Frame<double>* frames = Frames(p0.triangle);
    const kernel::Placed<double> p = kernel::PlaceInTriangle(frames, p0.distance.data());
    const kernel::Placed<double> q = kernel::PlaceInTriangle(frames, q0.distance.data());
    double best = std::numeric_limits<double>::infinity();
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
  // Rows of q's corners: the entries Prefetch brings in.
  if (!(Matrix(q.corner[0], p.corner[0]) < std::numeric_limits<double>::infinity()))
    return std::numeric_limits<double>::infinity();  // different components
  return kernel::FarDistance(GatherFar(p, q));
}

inline kernel::FarPair LiftedUnfolding::GatherFar(const LiftedPoint& p,
                                                  const LiftedPoint& q) const {
  kernel::FarPair pair;
  pair.p_frames = Frames(p.triangle);
  pair.q_frames = Frames(q.triangle);
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

inline bool LiftedUnfolding::AreNear(const LiftedPoint& a, const LiftedPoint& b) const {
  if (a.triangle == b.triangle) return true;
  for (int i = 0; i < 3; ++i) {
    if (triangles_[a.triangle].neighbor[i] == b.triangle) return true;
  }
  return false;
}

}  // namespace geodex::query
