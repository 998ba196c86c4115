#pragma once

// The arithmetic of a far-pair distance (Xin, Ying & He 2012, §5.2: case 2.2,
// then case 2.2 again), written once for one pair (T = double) and for
// kLanes pairs at a time (T = Lanes, a GCC vector of doubles), so that
// DistanceBatch computes several pairs per instruction with results
// bit-identical to a single query. There are no branches on values: both
// sides of every decision are computed and one is selected, as the lanes
// need; each select keeps the operand order and rounding of the scalar
// formula it replaces (and the project compiles in ISO mode, so nothing is
// contracted into fused multiply-adds). Internal to core/query.
//
// The lanes pay off with AVX2 (4 doubles per instruction); baseline x86-64
// has 2, and measured slower than one pair at a time. FarDistances picks
// the AVX2 code (unfold_kernel_avx2.cc, the one file built with -mavx2) at
// run time when the CPU has it. The functions live in an inline namespace
// named after the instruction set they are compiled for, so the copies in
// that file and in the others never merge at link time.

#include <cmath>
#include <limits>

#include "core/geometry/planar_unfolding.h"

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace geodex::query::kernel {

inline constexpr int kLanes = 4;

// An unfolded geodesic triangle seen from one of its edges: corner i at the
// origin, corner i+1 at (l, 0), the third corner at (cx, cy), cy >= 0;
// inv_2l = 1 / (2 l), or 0 for a degenerate edge (l = 0).
template <typename T>
struct Frame {
  T l, cx, cy, inv_2l;
};

// A point of a geodesic triangle placed in the triangle's three edge frames.
template <typename T>
struct Placed {
  T x[3], y[3];
};

// What FarDistance reads for one pair: p is the point in the triangle of
// smaller id, each given by its triangle's three edge frames and its
// distances to the triangle's corners; e[j][i] is the sample distance
// between q's corner j and p's corner i; shared[j] is p's exact distance to
// q's corner j when that corner is also p's (case 2.1), else -1.
struct FarPair {
  const Frame<double>* p_frames;
  const Frame<double>* q_frames;
  const double* p_distance;
  const double* q_distance;
  double e[3][3];
  double shared[3];
};

// out[k] = FarDistance(pairs[k]) for k < kLanes: all four in one pass of
// AVX2 instructions when this build and the CPU have them
// (HasAvx2Lanes()), else one pair at a time (FarDistancesOneByOne). The
// results are the same to the bit.
void FarDistances(const FarPair* pairs, double* out);
bool HasAvx2Lanes();
void FarDistancesOneByOne(const FarPair* pairs, double* out);
// Defined in unfold_kernel_avx2.cc; call only when HasAvx2Lanes().
void FarDistancesAvx2(const FarPair* pairs, double* out);

// For tests of the lanes against one point at a time: out[k] =
// PlaceInTriangle(frames[k], d[k]) for k < kLanes, computed in AVX2 lanes.
// Defined in unfold_kernel_avx2.cc; call only when HasAvx2Lanes().
void PlaceInTriangleAvx2(const Frame<double>* const* frames, const double* const* d,
                         Placed<double>* out);

#if defined(__AVX2__)
inline namespace avx2 {
#else
inline namespace baseline {
#endif

inline double Select(bool m, double a, double b) { return m ? a : b; }
inline bool And(bool a, bool b) { return a && b; }
inline bool Not(bool a) { return !a; }
inline double Sqrt(double x) { return std::sqrt(x); }

#if defined(__AVX2__)
using Lanes = double __attribute__((vector_size(kLanes * sizeof(double))));
using LaneMask = decltype(Lanes{} < Lanes{});

// Lanes{value(0), ..., value(kLanes - 1)}.
template <typename F>
inline Lanes MakeLanes(F&& value) {
  static_assert(kLanes == 4);
  return Lanes{value(0), value(1), value(2), value(3)};
}

// Per lane: m ? a : b, &&, !, std::sqrt (IEEE-exact, as vsqrtpd is).
inline Lanes Select(LaneMask m, Lanes a, Lanes b) { return m ? a : b; }
inline LaneMask And(LaneMask a, LaneMask b) { return a & b; }
inline LaneMask Not(LaneMask a) { return ~a; }
inline Lanes Sqrt(Lanes x) { return Lanes(_mm256_sqrt_pd(__m256d(x))); }
#endif

// std::min(a, b) and std::max(v, 0.0), NaN handling included.
template <typename T>
inline T Min(T a, T b) {
  return Select(b < a, b, a);
}
template <typename T>
inline T Max0(T v) {
  return Select(v < 0.0, T{}, v);
}

// Places a point at distances (da, db) from the edge's ends, y >= 0;
// distances that break the triangle inequality are clamped onto the edge.
// geometry::Place with the frame's stored 1 / (2 l).
template <typename T>
inline void PlaceOn(const Frame<T>& e, T da, T db, T* x, T* y) {
  *x = geometry::AlongEdgeInv2l(e.l, e.inv_2l, da, db);
  *y = Sqrt(Max0(geometry::HeightSquared(da, *x)));
}

// True when a placement at height y from distance d is almost on the edge's
// line, where sqrt(d^2 - x^2) loses half its digits to cancellation (the
// distances are float32).
template <typename T>
inline auto Weak(T y, T d, double limit) {
  return y * y < limit * d * d;
}

// Like PlaceOn, on the side of the edge whose mirror image matches the
// distance dc to the third corner better: points beyond an edge of the
// triangle (common near mesh boundaries and for far samples) thus land
// outside it. A degenerate edge gives (0, da).
template <typename T>
inline void PlaceSigned(const Frame<T>& e, T da, T db, T dc, T* x, T* y) {
  PlaceOn(e, da, db, x, y);
  // Squared distances to the third corner from (x, +y) and (x, -y) differ
  // by 4 y cy; pick the side whose value is nearer dc^2.
  const T dx = *x - e.cx;
  *y = Select(dc * dc > dx * dx + *y * *y + e.cy * e.cy, -*y, *y);
  const auto valid = e.l > 0.0;
  *x = Select(valid, *x, T{});
  *y = Select(valid, *y, da);
}

// Places a point at distances d[] from the corners in each edge frame.
template <typename T>
inline Placed<T> PlaceInTriangle(const Frame<T>* frames, const T* d) {
  Placed<T> out;
  for (int i = 0; i < 3; ++i) {
    const Frame<T>& e = frames[i];
    const T da = d[i], dc = d[(i + 2) % 3];
    PlaceSigned(e, da, d[(i + 1) % 3], dc, &out.x[i], &out.y[i]);
    // Near the edge's line: take the height from the third corner instead
    // (linear, conditioned by the triangle's height; the point is near).
    const T from_third = geometry::HeightFromThirdCorner(e.cx, e.cy, out.x[i], da, dc);
    out.y[i] = Select(And(Weak(out.y[i], da, 1e-4), e.cy > 1e-3 * e.l), from_third, out.y[i]);
  }
  return out;
}

// Paper §5.2, case 2.2: the squared distance from a placed point to a point
// outside its triangle at distances e[] from the corners, unfolded on the far
// side of each edge (two-side unfolding); the smallest over the edges. On a
// developable surface the edge the geodesic crosses gives the exact answer
// and the others overestimate.
template <typename T>
inline T TwoSideToOutside2(const Frame<T>* frames, const Placed<T>& p, const T* e) {
  // Relative rounding of squared float32 distances, with a margin.
  constexpr double kSameSide = 1 - 1e-6;
  // Weak placements of the other point (see Weak) only count when every
  // edge gives one. Within 1% of the edge's line (in height over distance)
  // a placement's float32 rounding is amplified a hundredfold; another edge
  // then places the point better.
  constexpr double kWeakOther = 1e-4;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  T best = T{} + kInf, best_collinear = T{} + kInf;
  for (int i = 0; i < 3; ++i) {
    const Frame<T>& f = frames[i];
    const T ek = e[(i + 2) % 3];
    T xs, ys;
    PlaceOn(f, e[i], e[(i + 1) % 3], &xs, &ys);
    const T dx = xs - f.cx, dy = ys - f.cy;
    // p inside this edge's half-plane: mirror the other point across the
    // edge (two-side) unless the third distance says that it is on this
    // side, no farther from the third corner than the same-side placement,
    // to rounding. Exact agreement is what a developable surface gives for
    // a point beside the triangle (round a shared corner); mirroring it
    // there would put it too close.
    const T two_side = Select(Not(ek * ek * kSameSide < dx * dx + dy * dy), -ys, ys);
    // p itself beyond this edge (outside its triangle, as near mesh
    // boundaries): mirroring the other point would bring it closer, so
    // place it on the side its distances say (PlaceSigned).
    const T signed_side = Select(ek * ek > dx * dx + ys * ys + f.cy * f.cy, -ys, ys);
    ys = Select(p.y[i] >= 0.0, two_side, signed_side);
    const T px = p.x[i] - xs, py = p.y[i] - ys;
    const T d2 = px * px + py * py;
    const auto valid = f.l > 0.0;
    const auto weak = Weak(ys, e[i], kWeakOther);
    best = Select(And(valid, Not(weak)), Min(best, d2), best);
    best_collinear = Select(And(valid, weak), Min(best_collinear, d2), best_collinear);
  }
  return Select(best < kInf, best, best_collinear);
}

// The far-pair distance (see FarPair): p's distances to q's corners by case
// 2.2 in p's triangle (or shared[j] when >= 0), then case 2.2 in q's
// triangle.
template <typename T>
inline T FarDistance(const Frame<T>* p_frames, const T* p_distance, const Frame<T>* q_frames,
                     const T* q_distance, const T (&e)[3][3], const T* shared) {
  const Placed<T> p_placed = PlaceInTriangle(p_frames, p_distance);
  T to_corner[3];
  for (int j = 0; j < 3; ++j) {
    to_corner[j] =
        Select(shared[j] >= 0.0, shared[j], Sqrt(TwoSideToOutside2(p_frames, p_placed, e[j])));
  }
  return Sqrt(TwoSideToOutside2(q_frames, PlaceInTriangle(q_frames, q_distance), to_corner));
}

inline double FarDistance(const FarPair& pair) {
  return FarDistance<double>(pair.p_frames, pair.p_distance, pair.q_frames, pair.q_distance, pair.e,
                             pair.shared);
}

}  // inline namespace
}  // namespace geodex::query::kernel
