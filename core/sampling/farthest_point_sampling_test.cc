#include "core/sampling/farthest_point_sampling.h"

#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include "core/mesh/generators.h"
#include "gtest/gtest.h"

namespace geodex::sampling {
namespace {

namespace gen = mesh::gen;

TEST(FarthestPointSamplingTest, IncrementalDistancesEqualOneMultiSourcePropagation) {
  const mesh::Mesh m = gen::Torus(40, 20, 2.0, 0.7);
  auto set = FarthestPointSampling(m, 25, 7);
  ASSERT_TRUE(set.ok()) << set.status();
  ASSERT_EQ(set->samples.size(), 25u);
  EXPECT_EQ(std::set<int32_t>(set->samples.begin(), set->samples.end()).size(), 25u);
  std::vector<mesh::SurfacePoint> sources;
  for (int32_t v : set->samples) sources.push_back(*mesh::VertexPoint(m, v));
  geodesic::ExactGeodesicSolver solver(m);
  ASSERT_TRUE(solver.Propagate(sources).ok());
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    EXPECT_NEAR(set->distance[v], solver.VertexDistance(v), 1e-12);
    // Labels agree wherever the nearest sample is unambiguous.
    const int32_t label = set->nearest[v];
    ASSERT_GE(label, 0);
    EXPECT_NEAR(solver.VertexDistance(v), set->distance[v], 1e-12);
  }
  for (size_t a = 0; a < set->samples.size(); ++a) {
    EXPECT_EQ(set->distance[set->samples[a]], 0);
    EXPECT_EQ(set->nearest[set->samples[a]], static_cast<int32_t>(a));
  }
}

TEST(FarthestPointSamplingTest, DeterministicForASeedAndDifferentAcrossSeeds) {
  const mesh::Mesh m = gen::Sphere(3, 1.0);
  auto a = FarthestPointSampling(m, 30, 1), b = FarthestPointSampling(m, 30, 1);
  auto c = FarthestPointSampling(m, 30, 2);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_EQ(a->samples, b->samples);
  EXPECT_EQ(a->nearest, b->nearest);
  EXPECT_NE(a->samples, c->samples);
}

TEST(FarthestPointSamplingTest, CoverageRadiusShrinks) {
  const mesh::Mesh m = gen::Sphere(3, 1.0);
  double previous = 1e9;
  for (int32_t count : {10, 40, 160}) {
    auto set = FarthestPointSampling(m, count, 3);
    ASSERT_TRUE(set.ok());
    const double radius = *std::max_element(set->distance.begin(), set->distance.end());
    EXPECT_LT(radius, previous);
    previous = radius;
  }
}

TEST(FarthestPointSamplingTest, EveryComponentIsSampled) {
  const mesh::Mesh m = gen::TwoComponents(8);
  auto set = FarthestPointSampling(m, 2, 5);
  ASSERT_TRUE(set.ok());
  std::set<int32_t> components;
  for (int32_t v : set->samples) components.insert(m.VertexComponent(v));
  EXPECT_EQ(components.size(), 2u);
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    EXPECT_LT(set->distance[v], geodesic::kInfinity);
  }
}

TEST(FarthestPointSamplingTest, RejectsImpossibleCounts) {
  const mesh::Mesh m = gen::Grid(2, 2, 1, 1);
  EXPECT_EQ(FarthestPointSampling(m, 0, 1).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(FarthestPointSampling(m, 10, 1).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(FarthestPointSamplingTest, SpacingWeightsCrowdSamplesWhereTheyAreLarge) {
  // A 2 x 1 sheet whose left half weighs 3, right half 1: the left half's
  // samples lie about three times closer together, so it takes about nine
  // times as many (density ~ weight^2); equal weights change nothing.
  const mesh::Mesh m = gen::Grid(80, 40, 2.0, 1.0);
  std::vector<double> weight(m.num_vertices());
  for (int32_t v = 0; v < m.num_vertices(); ++v) weight[v] = m.position(v).x() < 1.0 ? 3.0 : 1.0;
  auto set = FarthestPointSampling(m, 100, 1, weight);
  ASSERT_TRUE(set.ok()) << set.status();
  int left = 0;
  for (int32_t v : set->samples) left += m.position(v).x() < 1.0;
  EXPECT_GE(left, 80);
  EXPECT_LE(left, 95);
  const std::vector<double> equal(m.num_vertices(), 2.5);
  EXPECT_EQ(FarthestPointSampling(m, 100, 1, equal)->samples,
            FarthestPointSampling(m, 100, 1)->samples);
}

TEST(FarthestPointSamplingTest, RejectsBadSpacingWeights) {
  const mesh::Mesh m = gen::Grid(4, 4, 1, 1);
  std::vector<double> weight(m.num_vertices(), 1.0);
  weight.pop_back();
  EXPECT_EQ(FarthestPointSampling(m, 3, 1, weight).status().code(),
            absl::StatusCode::kInvalidArgument);
  for (double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    std::vector<double> w(m.num_vertices(), 1.0);
    w[3] = bad;
    EXPECT_EQ(FarthestPointSampling(m, 3, 1, w).status().code(), absl::StatusCode::kInvalidArgument)
        << bad;
  }
}

}  // namespace
}  // namespace geodex::sampling
