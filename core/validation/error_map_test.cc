#include "core/validation/error_map.h"

#include <cmath>

#include "core/builder/builder.h"
#include "core/mesh/generators.h"
#include "core/build/build_testing.h"
#include "gtest/gtest.h"

namespace geodex::validation {
namespace {

std::shared_ptr<const index::Index> IndexOf(
    const mesh::Mesh& m, int32_t samples,
    index::MatrixLayout matrix = index::MatrixLayout::kCoded) {
  absl::StatusOr<std::string> bytes = testing::BuildTestIndex(m, samples, false, matrix);
  if (!bytes.ok()) throw std::runtime_error(bytes.status().ToString());
  absl::StatusOr<std::shared_ptr<const index::Index>> index =
      index::Index::FromBytes(*std::move(bytes));
  if (!index.ok()) throw std::runtime_error(index.status().ToString());
  return *index;
}

// The area-weighted mean of a map.
double MeanOf(const mesh::Mesh& m, const std::vector<double>& map) {
  double sum = 0, area = 0;
  for (int32_t f = 0; f < m.num_faces(); ++f) {
    for (int32_t v : m.face(f)) {
      sum += m.Area(f) * map[v];
      area += m.Area(f);
    }
  }
  return sum / area;
}

TEST(ErrorMapTest, FlatWhereTheUnfoldingIsExactCurvedWhereItIsNot) {
  // A flat sheet unfolds exactly: no error anywhere but the float32
  // matrix's rounding. A sphere of the same sampling density errs everywhere.
  const mesh::Mesh flat = mesh::gen::Grid(40, 40, 2.0, 2.0);
  ErrorMapOptions options;
  options.num_sources = 8;
  auto flat_map = VertexErrorMap(flat, IndexOf(flat, 60, index::MatrixLayout::kFull), options);
  ASSERT_TRUE(flat_map.ok()) << flat_map.status();
  ASSERT_EQ(flat_map->size(), static_cast<size_t>(flat.num_vertices()));
  for (double e : *flat_map) EXPECT_LT(e, 1e-10);

  const mesh::Mesh sphere = mesh::gen::Sphere(4, 1.0);
  auto sphere_map = VertexErrorMap(sphere, IndexOf(sphere, 150), options);
  ASSERT_TRUE(sphere_map.ok()) << sphere_map.status();
  // Relative RMS between 0.1% and 10%: measured, not vacuous.
  const double rms = std::sqrt(MeanOf(sphere, *sphere_map));
  EXPECT_GT(rms, 1e-3);
  EXPECT_LT(rms, 0.1);
  for (double e : *sphere_map) EXPECT_TRUE(e >= 0 && std::isfinite(e));
}

TEST(ErrorMapTest, ConstantOverEachGeodesicTriangleAndTheSameOnAnyThreadCount) {
  const mesh::Mesh m = mesh::gen::Torus(48, 24, 2.0, 0.7);
  const auto index = IndexOf(m, 120);
  ErrorMapOptions options;
  options.num_sources = 6;
  options.threads = 1;
  auto one = VertexErrorMap(m, index, options);
  options.threads = 3;
  auto three = VertexErrorMap(m, index, options);
  ASSERT_TRUE(one.ok() && three.ok());
  EXPECT_EQ(*one, *three);
  const auto records = index->vertices();
  int shared = 0;
  for (int32_t f = 0; f < m.num_faces(); ++f) {
    const mesh::Triangle& t = m.face(f);
    for (int k = 0; k < 3; ++k) {
      const int32_t a = t[k], b = t[(k + 1) % 3];
      if (records[a].triangle != records[b].triangle) continue;
      EXPECT_EQ((*one)[a], (*one)[b]);
      ++shared;
    }
  }
  EXPECT_GT(shared, m.num_faces());
  EXPECT_EQ(VertexErrorMap(mesh::gen::Sphere(2, 1.0), index).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

TEST(SpacingWeightsTest, PowerOfTheErrorOverItsMeanAndPositiveEverywhere) {
  const mesh::Mesh m = mesh::gen::Grid(2, 2, 1.0, 1.0);  // 9 vertices
  std::vector<double> map(m.num_vertices(), 1e-4);
  map[4] = 64e-4;  // the centre
  map[0] = 0;      // a corner measured no error
  auto weight = SpacingWeights(m, map, 0.5);
  ASSERT_TRUE(weight.ok()) << weight.status();
  const double mean = MeanOf(m, map);
  EXPECT_NEAR((*weight)[4], std::sqrt(64e-4 / mean), 1e-12);
  EXPECT_NEAR((*weight)[1], std::sqrt(1e-4 / mean), 1e-12);
  EXPECT_EQ((*weight)[0], (*weight)[1]);  // the smallest positive weight
  EXPECT_EQ(SpacingWeights(m, std::vector<double>(3, 0.0)).status().code(),
            absl::StatusCode::kInvalidArgument);
  map[2] = -1;
  EXPECT_EQ(SpacingWeights(m, map).status().code(), absl::StatusCode::kInvalidArgument);
  // No error anywhere: plain farthest-point sampling.
  EXPECT_EQ(*SpacingWeights(m, std::vector<double>(m.num_vertices(), 0.0)),
            std::vector<double>(m.num_vertices(), 1.0));
}

}  // namespace
}  // namespace geodex::validation
