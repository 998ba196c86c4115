#include "core/query/engine/internal/paths/gradient_path.h"

#include <cmath>

#include "core/mesh/generators.h"
#include "core/query/engine/internal/paths/path_straightening.h"
#include "core/query/engine/internal/query_parts_testing.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

TEST(GradientPathTest, StraightenedTracesOnAFoldedSheetAreTheUnfoldedSegment) {
  const mesh::Mesh flat = mesh::gen::Grid(12, 12, 2, 2);
  const mesh::Mesh folded = mesh::gen::FoldedSheet(12, 12, 2, 2, 1.5);
  const testing::QueryParts parts(folded, 25);
  for (int32_t f = 0; f + 150 < folded.num_faces(); f += 31) {
    const SurfacePoint a{f, {0.2, 0.3, 0.5}}, b{f + 150, {0.5, 0.25, 0.25}};
    const double want = (mesh::PositionOf(flat, a) - mesh::PositionOf(flat, b)).norm();
    absl::StatusOr<std::vector<PathPoint>> path =
        parts.paths.Shortest(a, b, GradientPaths::Search::kFull);
    ASSERT_TRUE(path.ok()) << path.status();
    EXPECT_EQ(path->front().point.face, a.face);
    EXPECT_EQ(path->back().point.face, b.face);
    EXPECT_NEAR(PathLength(*path), want, 1e-9 * (1 + want)) << "face " << f;
    // The raw trace is a surface path too: never shorter.
    absl::StatusOr<std::vector<PathPoint>> raw = parts.paths.Trace(a, b);
    ASSERT_TRUE(raw.ok()) << raw.status();
    EXPECT_GE(PathLength(*raw), want - 1e-9);
  }
}

TEST(GradientPathTest, PointsOnDifferentComponentsHaveNoPath) {
  // Two spheres apart: no trace joins them.
  const mesh::Mesh one = mesh::gen::Sphere(2, 1.0);
  std::vector<mesh::Vec3> positions(one.positions().begin(), one.positions().end());
  std::vector<mesh::Triangle> faces(one.faces().begin(), one.faces().end());
  const int32_t n = static_cast<int32_t>(positions.size()), m = one.num_faces();
  for (int32_t v = 0; v < n; ++v) positions.push_back(one.position(v) + mesh::Vec3(5, 0, 0));
  for (int32_t f = 0; f < m; ++f) {
    const mesh::Triangle& t = one.face(f);
    faces.push_back({t[0] + n, t[1] + n, t[2] + n});
  }
  const mesh::Mesh two = *mesh::Mesh::Create(positions, faces, "two spheres");
  const testing::QueryParts parts(two, 40);
  const absl::StatusOr<std::vector<PathPoint>> path = parts.paths.Shortest(
      {0, {0.2, 0.3, 0.5}}, {m + 3, {0.2, 0.3, 0.5}}, GradientPaths::Search::kFull);
  EXPECT_EQ(path.status().code(), absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace geodex::query
