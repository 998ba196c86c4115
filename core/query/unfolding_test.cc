#include "core/query/unfolding.h"

#include <cmath>
#include <random>

#include "core/mesh/generators.h"
#include "core/query/query_parts_testing.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

// Random interior points of a mesh.
std::vector<SurfacePoint> Points(const mesh::Mesh& m, int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<SurfacePoint> out;
  for (int i = 0; i < n; ++i) {
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    out.push_back({static_cast<int32_t>(u(rng) * m.num_faces()) % m.num_faces(), {a, b, 1 - a - b}});
  }
  return out;
}

TEST(UnfoldingTest, FlatSheetDistancesAreEuclidean) {
  // On a flat sheet every geodesic is straight and every unfolding is exact,
  // both in one triangle (case 3.1) and across triangles (case 3.2).
  const mesh::Mesh sheet = mesh::gen::Grid(12, 12, 2, 2);
  const testing::QueryParts parts(sheet, 30);
  const std::vector<SurfacePoint> points = Points(sheet, 120, 5);
  int same = 0, other = 0;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    const LiftedPoint p = parts.lifting.Lift(points[i]), q = parts.lifting.Lift(points[i + 1]);
    const double want = (mesh::PositionOf(sheet, points[i]) - mesh::PositionOf(sheet, points[i + 1])).norm();
    EXPECT_NEAR(parts.unfolding.Distance(p, q), want, 1e-5 * (1 + want));
    EXPECT_EQ(parts.unfolding.Distance(p, q), parts.unfolding.Distance(q, p));  // symmetric
    EXPECT_NEAR(parts.unfolding.Spread(p, q), 0, 1e-5);  // both orders exact
    (p.triangle == q.triangle ? same : other) += 1;
  }
  EXPECT_GT(same, 0);
  EXPECT_GT(other, 0);
}

TEST(UnfoldingTest, LanesEqualOneAtATime) {
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 60);
  const std::vector<SurfacePoint> points = Points(sphere, 64, 9);
  for (size_t i = 0; i + 2 * kernel::kLanes <= points.size(); i += 2 * kernel::kLanes) {
    LiftedPoint a[kernel::kLanes], b[kernel::kLanes];
    for (int k = 0; k < kernel::kLanes; ++k) {
      a[k] = parts.lifting.Lift(points[i + k]);
      b[k] = parts.lifting.Lift(points[i + kernel::kLanes + k]);
    }
    double out[kernel::kLanes];
    parts.unfolding.DistanceLanes(a, b, out);
    for (int k = 0; k < kernel::kLanes; ++k) EXPECT_EQ(out[k], parts.unfolding.Distance(a[k], b[k]));
  }
}

TEST(UnfoldingTest, ToSampleIsExactAtCornersAndNearTriangles) {
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 60);
  for (int32_t v = 0; v < 40; ++v) {
    const LiftedPoint p = parts.lifting.VertexLift(v);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(parts.unfolding.ToSample(p, p.corner[c]), p.distance[c]);
    EXPECT_TRUE(parts.unfolding.AreNear(p, p));
  }
  const index::GeodesicTriangle& t = parts.index->triangles()[0];
  LiftedPoint a, b;
  a.triangle = 0;
  b.triangle = t.neighbor[0];
  EXPECT_TRUE(parts.unfolding.AreNear(a, b));
  EXPECT_EQ(parts.unfolding.Matrix(t.corner[0], t.corner[0]), 0);
  EXPECT_GT(parts.unfolding.Matrix(t.corner[0], t.corner[1]), 0);
}

}  // namespace
}  // namespace geodex::query
