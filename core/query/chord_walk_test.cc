#include "core/query/chord_walk.h"

#include <cmath>

#include "core/mesh/generators.h"
#include "core/query/query_parts_testing.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

// The distance on a sheet of `width` folded at x = width / 2: the length in
// the unfolded plane (FoldedSheet is developable).
TEST(ChordWalkTest, NearPairsAcrossAFoldAreTheUnfoldedSegment) {
  const double width = 2, height = 2;
  const mesh::Mesh flat = mesh::gen::Grid(10, 10, width, height);
  const mesh::Mesh folded = mesh::gen::FoldedSheet(10, 10, width, height, 2.0);
  const testing::QueryParts parts(folded, 20);
  int straight = 0;
  for (int32_t f = 0; f + 23 < folded.num_faces(); f += 9) {
    const SurfacePoint a{f, {0.2, 0.3, 0.5}}, b{f + 23, {0.5, 0.25, 0.25}};
    // Same ids, same weights: the flat grid is the unfolding of the sheet.
    const double want = (mesh::PositionOf(flat, a) - mesh::PositionOf(flat, b)).norm();
    for (const bool walk : {true, false}) {
      const std::optional<NearPath> path = NearPathLength(parts.view, parts.paths, a, b, walk);
      ASSERT_TRUE(path.has_value()) << "face " << f;
      EXPECT_NEAR(path->length, want, 1e-9 * (1 + want)) << "face " << f << " walk " << walk;
      straight += !path->wraps;
    }
  }
  EXPECT_GT(straight, 0);
}

TEST(ChordWalkTest, ADoubtedWalkGivesWayToAShorterTrace) {
  // A plausible bound below every length: each walk is doubted, the trace
  // decides, and the answer is still a surface path (>= the geodesic).
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 40);
  const SurfacePoint a{3, {0.2, 0.3, 0.5}}, b{40, {0.5, 0.25, 0.25}};
  const std::optional<NearPath> free = NearPathLength(parts.view, parts.paths, a, b, true);
  const std::optional<NearPath> doubted =
      NearPathLength(parts.view, parts.paths, a, b, true, /*plausible=*/0);
  ASSERT_TRUE(free && doubted);
  const double chord = (mesh::PositionOf(sphere, a) - mesh::PositionOf(sphere, b)).norm();
  EXPECT_GE(free->length, chord);
  EXPECT_GE(doubted->length, chord);
  EXPECT_GE(doubted->length, free->length - 1e-12);
}

}  // namespace
}  // namespace geodex::query
