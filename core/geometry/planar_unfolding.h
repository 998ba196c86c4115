#pragma once

// The planar unfolding of Xin, Ying & He 2012, §5.1, written once: a point
// placed from its distances to the ends of an edge (law of cosines), a point
// trilaterated from its distances to the corners of a triangle, and the
// barycentric coordinates of an unfolded point. Shared by the builder
// (vertex -> triangle assignment), the query engine, the path tracer, the
// path straightener and the far-pair kernel (core/query/engine/internal/o1/unfold_kernel.h).
//
// The formulas are templates where the kernel evaluates them on a GCC
// vector of doubles (four pairs at a time), so that its lanes round exactly
// as one pair at a time does. Each keeps its operand order: the project
// compiles without -ffast-math and without FMA contraction, so equal
// operation orders give equal bits. Where two callers use formulas that are
// equal in real arithmetic but round differently (dividing by 2 l, or
// multiplying by a stored 1 / (2 l)), both are kept under their own names.
//
// Like the kernel, the functions live in an inline namespace named after the
// instruction set they are compiled for, so that the copies in the one file
// built with -mavx2 never merge with the others at link time.
//
// Thread safety: pure functions.

#include <algorithm>
#include <array>
#include <cmath>

namespace geodex::geometry {

#if defined(__AVX2__)
inline namespace avx2 {
#else
inline namespace baseline {
#endif

// The coordinate along an edge of length l (from its end a) of a point at
// distances (da, db) from the edge's ends: (l^2 + da^2 - db^2) / (2 l).
template <typename T>
inline T AlongEdge(T l, T da, T db) {
  return (l * l + da * da - db * db) / (2 * l);
}

// AlongEdge with a precomputed inv_2l = 1 / (2 l): a multiplication instead
// of a division (rounds differently from AlongEdge; the kernel's frames
// store inv_2l).
template <typename T>
inline T AlongEdgeInv2l(T l, T inv_2l, T da, T db) {
  return (l * l + da * da - db * db) * inv_2l;
}

// The squared height over the edge's line of a point at distance da from
// the edge's end a and at `along` from it along the edge; negative when the
// distances break the triangle inequality.
template <typename T>
inline T HeightSquared(T da, T along) {
  return da * da - along * along;
}

// Places a point at distances (da, db) from the ends of an edge of length l
// lying on the x axis: x along the edge, y >= 0 its height. Distances that
// break the triangle inequality (numerically, or because geodesic triangles
// are curved) are clamped onto the edge instead of giving NaN.
inline void Place(double l, double da, double db, double* x, double* y) {
  *x = AlongEdge(l, da, db);
  *y = std::sqrt(std::max(HeightSquared(da, *x), 0.0));
}

// The height of a point over the x axis in the plane of a triangle with
// corners (0, 0), (l, 0), (cx, cy), cy != 0, from its coordinate x along
// the axis and its distances d0, d2 to corners 0 and 2: linear, no square
// root, so well conditioned where Place's sqrt(d0^2 - x^2) is not (a point
// near the axis).
template <typename T>
inline T HeightFromThirdCorner(T cx, T cy, T x, T d0, T d2) {
  return (cx * cx + cy * cy - 2.0 * x * cx + d0 * d0 - d2 * d2) / (2.0 * cy);
}

// Trilateration: the point at distances d0, d1, d2 from the corners of the
// triangle (0, 0), (l, 0), (cx, cy), cy != 0 (the unfolded source of a field
// known exactly at the corners). Linear, no square roots.
inline void Trilaterate(double l, double cx, double cy, double d0, double d1, double d2, double* x,
                        double* y) {
  *x = AlongEdge(l, d0, d1);
  *y = HeightFromThirdCorner(cx, cy, *x, d0, d2);
}

// Two-side unfolding (§5.1): the squared distance from a point (xp, yp) to
// the point placed at (xq, yq) on the same side of the x axis (an edge),
// mirrored to the other side, (xq, -yq): the unfolding of the two triangles
// that share the edge.
template <typename T>
inline T TwoSideDistance2(T xp, T yp, T xq, T yq) {
  const T dx = xp - xq, dy = yp + yq;
  return dx * dx + dy * dy;
}

// Barycentric coordinates, in the planar triangle (a, b, c) with side
// lengths (ab, bc, ca), of the point at distances d from its corners: placed
// from d[0] and d[1] on the side of ab whose distance to c matches d[2]
// better. A degenerate triangle gives (1, 0, 0).
inline std::array<double, 3> UnfoldedBarycentric(double ab, double bc, double ca,
                                                 const std::array<double, 3>& d) {
  if (!(ab > 0)) return {1, 0, 0};
  double cx, cy, px, py;
  Place(ab, ca, bc, &cx, &cy);
  Place(ab, d[0], d[1], &px, &py);
  const double dx = px - cx;
  const double up = std::abs(std::sqrt(dx * dx + (py - cy) * (py - cy)) - d[2]);
  const double down = std::abs(std::sqrt(dx * dx + (py + cy) * (py + cy)) - d[2]);
  if (down < up) py = -py;
  const double area = ab * cy;  // twice the area
  if (!(area > 0)) return {1, 0, 0};
  const double lc = py / cy;
  const double lb = (px * cy - py * cx) / area;
  return {1 - lb - lc, lb, lc};
}

}  // inline namespace
}  // namespace geodex::geometry
