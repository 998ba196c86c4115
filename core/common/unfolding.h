#pragma once

// The planar unfolding of geodesic triangles (Xin, Ying & He 2012, §5.1),
// shared by the builder (vertex -> triangle assignment) and the query engine.

#include <algorithm>
#include <array>
#include <cmath>

namespace geodex {

// Places a point at distances (da, db) from the ends of an edge of length l
// lying on the x axis: x along the edge, y >= 0 its height. Distances that
// break the triangle inequality (numerically, or because geodesic triangles
// are curved) are clamped onto the edge instead of giving NaN.
inline void Place(double l, double da, double db, double* x, double* y) {
  *x = (l * l + da * da - db * db) / (2 * l);
  *y = std::sqrt(std::max(da * da - *x * *x, 0.0));
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

}  // namespace geodex
