#include "core/geometry/planar_unfolding.h"

#include <cmath>

#include "gtest/gtest.h"

namespace geodex::geometry {
namespace {

TEST(UnfoldingTest, PlaceOnARightTriangle) {
  // The 3-4-5 triangle: the apex at distances 3 and 5 from the ends of an
  // edge of length 4 sits above the first end.
  double x, y;
  Place(4, 3, 5, &x, &y);
  EXPECT_DOUBLE_EQ(x, 0);
  EXPECT_DOUBLE_EQ(y, 3);
  Place(4, 5, 3, &x, &y);
  EXPECT_DOUBLE_EQ(x, 4);
  EXPECT_DOUBLE_EQ(y, 3);
}

TEST(UnfoldingTest, PlaceClampsBrokenTriangleInequality) {
  double x, y;
  Place(1, 0.2, 2, &x, &y);  // 0.2 + 1 < 2: no triangle
  EXPECT_EQ(y, 0);
  EXPECT_TRUE(std::isfinite(x));
}

TEST(UnfoldingTest, TheTwoAlongEdgeFormsAgreeToRounding) {
  const double l = 1.7, da = 1.1, db = 0.9;
  EXPECT_NEAR(AlongEdge(l, da, db), AlongEdgeInv2l(l, 1 / (2 * l), da, db), 1e-15);
}

TEST(UnfoldingTest, TrilaterateRecoversThePoint) {
  // Triangle (0,0), (2,0), (0.5,1.5); point (0.7, 0.4).
  const double l = 2, cx = 0.5, cy = 1.5, px = 0.7, py = 0.4;
  const double d0 = std::hypot(px, py), d1 = std::hypot(px - l, py),
               d2 = std::hypot(px - cx, py - cy);
  double x, y;
  Trilaterate(l, cx, cy, d0, d1, d2, &x, &y);
  EXPECT_NEAR(x, px, 1e-14);
  EXPECT_NEAR(y, py, 1e-14);
  // A point below the axis too (Place alone would put it above).
  Trilaterate(l, cx, cy, d0, d1, std::hypot(px - cx, -py - cy), &x, &y);
  EXPECT_NEAR(y, -py, 1e-14);
}

TEST(UnfoldingTest, TwoSideDistanceMirrorsTheOtherPoint) {
  // Two unit right triangles sharing the edge (0,0)-(1,0): apexes (0, 1)
  // and, unfolded across the edge, (0, -1).
  EXPECT_DOUBLE_EQ(TwoSideDistance2(0.0, 1.0, 0.0, 1.0), 4.0);
  EXPECT_DOUBLE_EQ(TwoSideDistance2(1.0, 1.0, 0.0, 1.0), 5.0);
}

TEST(UnfoldingTest, UnfoldedBarycentricOfCornersAndCentroid) {
  // Equilateral triangle of side 1.
  const double h = 1 / std::sqrt(3.0);  // centroid to corner
  const std::array<double, 3> c = UnfoldedBarycentric(1, 1, 1, {h, h, h});
  for (double w : c) EXPECT_NEAR(w, 1.0 / 3, 1e-14);
  const std::array<double, 3> b = UnfoldedBarycentric(1, 1, 1, {1, 0, 1});
  EXPECT_NEAR(b[0], 0, 1e-14);
  EXPECT_NEAR(b[1], 1, 1e-14);
  EXPECT_NEAR(b[2], 0, 1e-14);
  // Degenerate: (1, 0, 0).
  EXPECT_EQ(UnfoldedBarycentric(0, 1, 1, {1, 1, 1}), (std::array<double, 3>{1, 0, 0}));
}

}  // namespace
}  // namespace geodex::geometry
