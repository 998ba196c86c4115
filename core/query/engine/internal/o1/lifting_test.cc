#include "core/query/engine/internal/o1/lifting.h"

#include <algorithm>
#include <cmath>

#include "core/mesh/generators.h"
#include "core/query/engine/internal/query_parts_testing.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

// The position of sample `s`.
mesh::Vec3 SamplePosition(const testing::QueryParts& parts, int32_t s) {
  return parts.view.Position(parts.index->samples()[s]);
}

TEST(LiftingTest, FlatSheetLiftsAreEuclideanDistancesToTheCorners) {
  // On a flat sheet every field is planar: lifted distances are exact for
  // vertices and interior points alike.
  const mesh::Mesh sheet = mesh::gen::Grid(10, 10, 2, 2);
  const testing::QueryParts parts(sheet, 25, index::MatrixLayout::kFull);
  for (int32_t f = 0; f < sheet.num_faces(); f += 7) {
    for (const std::array<double, 3>& w :
         {std::array<double, 3>{1.0 / 3, 1.0 / 3, 1.0 / 3}, std::array<double, 3>{0.7, 0.2, 0.1},
          std::array<double, 3>{0, 1, 0}}) {
      const SurfacePoint p{f, w};
      const LiftedPoint lp = parts.lifting.Lift(p);
      ASSERT_GE(lp.triangle, 0);
      for (int c = 0; c < 3; ++c) {
        const double want =
            (mesh::PositionOf(sheet, p) - SamplePosition(parts, lp.corner[c])).norm();
        EXPECT_NEAR(lp.distance[c], want, 1e-5 * (1 + want)) << "face " << f << " corner " << c;
      }
    }
  }
}

TEST(LiftingTest, AVertexLiftsToItsRecord) {
  const mesh::Mesh sphere = mesh::gen::Sphere(2, 1.0);
  const testing::QueryParts parts(sphere, 30);
  for (int32_t f = 0; f < sphere.num_faces(); f += 11) {
    for (int k = 0; k < 3; ++k) {
      SurfacePoint p{f, {0, 0, 0}};
      p.w[k] = 1;
      const LiftedPoint lp = parts.lifting.Lift(p);
      const LiftedPoint record = parts.lifting.VertexLift(sphere.face(f)[k]);
      EXPECT_EQ(lp.triangle, record.triangle);
      EXPECT_EQ(lp.corner, record.corner);
      EXPECT_EQ(lp.distance, record.distance);
    }
  }
}

TEST(LiftingTest, O1DistanceIsAtLeastTheChordForNearPairs) {
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 40);
  int near = 0;
  for (int32_t f = 0; f + 1 < sphere.num_faces(); f += 5) {
    const SurfacePoint p{f, {0.2, 0.3, 0.5}}, q{f + 1, {0.6, 0.2, 0.2}};
    const double d = O1Distance(parts.view, parts.lifting, parts.unfolding, p, q);
    const LiftedPoint lp = parts.lifting.Lift(p), lq = parts.lifting.Lift(q);
    const double unfolded = parts.unfolding.Distance(lp, lq);
    if (!parts.unfolding.AreNear(lp, lq)) {
      EXPECT_EQ(d, unfolded);  // far pairs: the unfolding as it is
      continue;
    }
    ++near;
    const double chord = (mesh::PositionOf(sphere, p) - mesh::PositionOf(sphere, q)).norm();
    EXPECT_EQ(d, std::max(unfolded, chord));
    EXPECT_EQ(d, O1Distance(parts.view, parts.lifting, parts.unfolding, q, p));
  }
  EXPECT_GT(near, 0);
}

}  // namespace
}  // namespace geodex::query
