#include "core/query/engine/internal/exact/local_exact.h"

#include <cmath>
#include <vector>

#include "core/build/build_testing.h"
#include "core/mesh/broken_meshes_testing.h"
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

// On a split index a pair's propagation runs on the surface before the
// split (flat, so the same distances on fewer faces): its answers to the
// split mesh's vertices, midpoints too, are the split mesh's own.
TEST(LocalExactTest, ASplitIndexsPairsAreTheSplitMeshsDistances) {
  const auto split = geodex::testing::RepairedTestEngineOrThrow(
      mesh::testing::RawOf(mesh::gen::Sphere(1, 1.0), "sphere"), 120, /*split=*/true);
  const index::Index& ix = split.engine->index();
  ASSERT_GT(ix.split_vertices(), 0);
  const MeshView view{ix.positions(), ix.faces(), ix.twins()};
  const LocalExact exact(ix, view);
  QueryScratch scratch;
  const int32_t first_midpoint = ix.num_vertices() - ix.split_vertices();
  int midpoints = 0, checked = 0;
  for (const int32_t f : {0, 17, 101}) {
    const SurfacePoint p{f, {0.2, 0.3, 0.5}};
    absl::StatusOr<std::span<const double>> field = exact.Distances(p, 10, scratch);
    ASSERT_TRUE(field.ok()) << field.status();
    const std::vector<double> want(field->begin(), field->end());
    for (int32_t g = 0; g < ix.num_faces(); g += 5) {
      const int32_t v = view.Vertex(g, 0);
      const SurfacePoint q{g, {1, 0, 0}};
      const std::optional<double> near = exact.NearDistance(p, q, &scratch);
      const std::optional<double> confined = exact.ConfinedDistance(p, q, {}, scratch);
      ASSERT_TRUE(near.has_value() && confined.has_value()) << "face " << g;
      EXPECT_NEAR(*near, want[v], 1e-9 * (1 + want[v])) << "vertex " << v;
      EXPECT_NEAR(*confined, want[v], 1e-9 * (1 + want[v])) << "vertex " << v;
      midpoints += v >= first_midpoint;
      ++checked;
    }
  }
  EXPECT_GT(midpoints, 0);
  EXPECT_GT(checked, 100);
}

}  // namespace
}  // namespace geodex::query
