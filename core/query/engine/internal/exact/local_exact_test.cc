#include "core/query/engine/internal/exact/local_exact.h"

#include <cmath>

#include "core/mesh/generators.h"
#include "core/query/engine/internal/paths/path_straightening.h"
#include "core/query/engine/internal/query_parts_testing.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

TEST(LocalExactTest, DistancesOnAFlatSheetAreEuclideanWithinTheRadius) {
  const mesh::Mesh sheet = mesh::gen::Grid(10, 10, 2, 2);
  const testing::QueryParts parts(sheet, 20);
  QueryScratch scratch;
  const SurfacePoint p{57, {0.2, 0.3, 0.5}};
  absl::StatusOr<std::span<const double>> d = parts.exact.Distances(p, 0.6, scratch);
  ASSERT_TRUE(d.ok()) << d.status();
  int inside = 0;
  for (int32_t v = 0; v < sheet.num_vertices(); ++v) {
    const double want = (sheet.position(v) - mesh::PositionOf(sheet, p)).norm();
    if (want <= 0.6) {
      EXPECT_NEAR((*d)[v], want, 1e-9) << "vertex " << v;
      ++inside;
    } else {
      EXPECT_GT((*d)[v], 0.6 - 1e-9) << "vertex " << v;
    }
  }
  EXPECT_GT(inside, 10);
  EXPECT_EQ(parts.exact.Distances(p, -1, scratch).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(LocalExactTest, NearDistanceIsTheGeodesicOverAFold) {
  const mesh::Mesh flat = mesh::gen::Grid(10, 10, 2, 2);
  const mesh::Mesh folded = mesh::gen::FoldedSheet(10, 10, 2, 2, 2.5);
  const testing::QueryParts parts(folded, 20);
  QueryScratch scratch;
  const SurfacePoint a{12, {0.2, 0.3, 0.5}}, b{170, {0.5, 0.25, 0.25}};
  const std::optional<double> d = parts.exact.NearDistance(a, b, &scratch);
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(*d, (mesh::PositionOf(flat, a) - mesh::PositionOf(flat, b)).norm(), 1e-9);
  // Without a scratch the answer is the same.
  EXPECT_EQ(parts.exact.NearDistance(a, b, nullptr), d);
}

TEST(LocalExactTest, CorridorPathIsExactAndNeverLongerThanTheTrace) {
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 30);
  const SurfacePoint a{4, {0.2, 0.3, 0.5}}, b{300, {0.5, 0.25, 0.25}};
  absl::StatusOr<std::vector<PathPoint>> raw = parts.paths.Trace(a, b);
  ASSERT_TRUE(raw.ok()) << raw.status();
  absl::StatusOr<std::vector<PathPoint>> exact = parts.exact.CorridorPath(*raw, 3);
  ASSERT_TRUE(exact.ok()) << exact.status();
  EXPECT_LE(PathLength(*exact), PathLength(*raw) + 1e-12);
  EXPECT_NEAR((exact->front().position - mesh::PositionOf(sphere, a)).norm(), 0, 1e-9);
  EXPECT_NEAR((exact->back().position - mesh::PositionOf(sphere, b)).norm(), 0, 1e-9);
}

}  // namespace
}  // namespace geodex::query
