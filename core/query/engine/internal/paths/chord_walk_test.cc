#include "core/query/engine/internal/paths/chord_walk.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/mesh/generators.h"
#include "core/query/engine/internal/query_parts_testing.h"
#include "core/query/engine/query_scratch.h"
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

// A saddle: eight equilateral triangles round a vertex c (480 degrees),
// split twice. A geodesic between points whose angle round c is at least
// pi on both sides passes through c (length r_p + r_q); else it is the
// straight segment in the unfolding of the shorter side.
TEST(ChordWalkTest, NearPairsRoundASaddleVertexAreExact) {
  constexpr int kSectors = 8;
  const double r = std::sqrt(3 / (4 - 4 * std::pow(std::sin(M_PI / kSectors), 2))),
               z = std::sqrt(1 - r * r);
  std::vector<mesh::Vec3> positions = {{0, 0, 0}};
  std::vector<mesh::Triangle> faces;
  for (int i = 0; i < kSectors; ++i) {
    const double t = 2 * M_PI * i / kSectors;
    positions.push_back({r * std::cos(t), r * std::sin(t), i % 2 ? z : -z});
    faces.push_back({0, 1 + i, 1 + (i + 1) % kSectors});
  }
  const absl::StatusOr<mesh::Mesh> fan = mesh::Mesh::Create(positions, faces, "saddle");
  ASSERT_TRUE(fan.ok()) << fan.status();
  const mesh::Mesh saddle = mesh::gen::SplitFacesInFour(*fan, 3);
  const testing::QueryParts parts(saddle, 12);
  const double total = kSectors * M_PI / 3;
  // A point's distance from c and its angle round c from the first edge.
  auto polar = [&](const mesh::Vec3& x, double* radius) {
    *radius = x.norm();
    const double t = std::atan2(x.y(), x.x());
    const int sector = static_cast<int>(std::floor((t < 0 ? t + 2 * M_PI : t) / (M_PI / 4)));
    const mesh::Vec3 edge = positions[1 + sector % kSectors];
    return sector * M_PI / 3 +
           std::acos(std::clamp(x.dot(edge) / (*radius * edge.norm()), -1.0, 1.0));
  };
  int through_c = 0, checked = 0;
  for (int32_t f = 0; f < saddle.num_faces(); f += 7) {
    for (int32_t g = f + 3; g < saddle.num_faces(); g += 11) {
      const SurfacePoint a{f, {0.2, 0.3, 0.5}}, b{g, {0.5, 0.25, 0.25}};
      double ra, rb;
      const double ta = polar(mesh::PositionOf(saddle, a), &ra);
      const double tb = polar(mesh::PositionOf(saddle, b), &rb);
      // Within 0.4 of c segments in the unfolding stay off the rim.
      if (ra > 0.4 || rb > 0.4) continue;
      const double side = std::min(std::abs(ta - tb), total - std::abs(ta - tb));
      const double want =
          side >= M_PI ? ra + rb : std::sqrt(ra * ra + rb * rb - 2 * ra * rb * std::cos(side));
      const std::optional<NearPath> path = NearPathLength(parts.view, parts.paths, a, b, true);
      ASSERT_TRUE(path.has_value());
      EXPECT_NEAR(path->length, want, 1e-9 * want) << "faces " << f << " " << g;
      through_c += side >= M_PI;
      ++checked;
    }
  }
  EXPECT_GT(checked, 50);
  EXPECT_GT(through_c, 10);
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

// The walks keep their corridors and layouts in a scratch from pair to
// pair, and a release lays out only the faces after its bend: neither may
// change an answer. A scratch kept over many pairs, releases among them,
// gives what a fresh one gives, to the bit.
TEST(ChordWalkTest, AKeptScratchAndReleasedLayoutsGiveTheAnswersOfFreshOnes) {
  // The inside of a torus is a field of saddle vertices: walks release.
  const mesh::Mesh torus = mesh::gen::Torus(48, 24, 1.0, 0.45);
  const testing::QueryParts parts(torus, 60);
  QueryScratch kept;
  int compared = 0, released = 0;
  for (int32_t f = 0; f < torus.num_faces(); f += 13) {
    for (const int32_t step : {5, 37, 101, 151}) {
      const int32_t g = (f + step) % torus.num_faces();
      SurfacePoint a{f, {0.2, 0.3, 0.5}}, b{g, {0.5, 0.25, 0.25}};
      if (g < f) std::swap(a, b);
      const int64_t releases = kept.near_pair_stats().releases;
      const NearWalk walk = WalkNearPair(parts.view, a, b, {}, &kept);
      QueryScratch own;
      const NearWalk fresh = WalkNearPair(parts.view, a, b, {}, &own);
      EXPECT_TRUE(WalkNearPair(parts.view, a, b).corridor.empty());  // its scratch is gone
      ASSERT_EQ(walk.path.has_value(), fresh.path.has_value()) << f << " " << g;
      ASSERT_EQ(walk.doubted.has_value(), fresh.doubted.has_value()) << f << " " << g;
      if (walk.doubted) {
        EXPECT_EQ(*walk.doubted, *fresh.doubted) << f << " " << g;
      }
      EXPECT_TRUE(std::equal(walk.corridor.begin(), walk.corridor.end(), fresh.corridor.begin(),
                             fresh.corridor.end()));
      if (!walk.path) continue;
      ++compared;
      EXPECT_EQ(walk.path->length, fresh.path->length) << f << " " << g;
      EXPECT_EQ(walk.path->wraps, fresh.path->wraps) << f << " " << g;
      if (kept.near_pair_stats().releases > releases) ++released;
    }
  }
  EXPECT_GT(compared, 100);
  // Most pairs are settled by straight shots; a few corridors still need
  // releases.
  EXPECT_GT(released, 2);
}

// Shots on a developable surface whose chord leaves it: a cylinder, where
// the geodesic between points far apart round it is a helix, straight in
// the unrolled prism, and the chord runs through the inside. The shots,
// aimed first along the chord, settle on the straight geodesic: its length
// is the exact engine's, and most pairs take one or two shots.
TEST(ChordWalkTest, ShotsFindTheStraightGeodesicRoundACylinder) {
  const mesh::Mesh cylinder = mesh::gen::Cylinder(24, 24, 1.0, 4.0);
  const testing::QueryParts parts(cylinder, 40);
  QueryScratch scratch;
  int pairs = 0, shot_straight = 0;
  for (int32_t f = 0; f < cylinder.num_faces(); f += 37) {
    const int32_t g = (f + 7 * 48 + 19) % cylinder.num_faces();  // a quarter turn and more away
    SurfacePoint a{f, {0.2, 0.3, 0.5}}, b{g, {0.5, 0.25, 0.25}};
    if (g < f) std::swap(a, b);
    const std::optional<double> exact = parts.exact.NearDistance(a, b, &scratch);
    ASSERT_TRUE(exact.has_value());
    // Shots are taken under a check (the refinement's: the O(1) answer plus
    // its bound), here a generous one.
    const NearPairStats before = scratch.near_pair_stats();
    const NearWalk walk =
        WalkNearPair(parts.view, a, b, {.plausible = 1.2 * *exact, .shoot = true}, &scratch);
    ++pairs;
    if (!walk.path) continue;
    EXPECT_GE(walk.path->length, *exact * (1 - 1e-9)) << f << " " << g;  // a surface path
    const NearPairStats& after = scratch.near_pair_stats();
    int64_t straight = 0;
    for (int k = 0; k < 4; ++k) straight += after.straight_at_shot[k] - before.straight_at_shot[k];
    if (straight == 0) continue;
    ++shot_straight;
    EXPECT_FALSE(walk.path->wraps);
    EXPECT_NEAR(walk.path->length, *exact, 1e-9 * (1 + *exact)) << f << " " << g;
  }
  EXPECT_GT(pairs, 20);
  EXPECT_GE(shot_straight, pairs * 3 / 4) << shot_straight << " of " << pairs;
  EXPECT_GT(scratch.near_pair_stats().shots, 0);
}

// Shots aimed along the chord or by the O(1) field (GradientPaths::Heading)
// find paths within 1% of the geodesic on a convex surface.
TEST(ChordWalkTest, ShotsAimedAlongTheChordOrByTheFieldFindTheGeodesic) {
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 60);
  QueryScratch by_chord, by_field;
  for (int32_t f = 0; f < sphere.num_faces(); f += 11) {
    const int32_t g = (f + 97) % sphere.num_faces();
    SurfacePoint a{f, {0.2, 0.3, 0.5}}, b{g, {0.5, 0.25, 0.25}};
    if (g < f) std::swap(a, b);
    const std::optional<double> exact = parts.exact.NearDistance(a, b, &by_field);
    ASSERT_TRUE(exact.has_value());
    const double plausible = 1.2 * *exact;  // a generous check, as in the cylinder's test
    const NearWalk chord =
        WalkNearPair(parts.view, a, b, {.plausible = plausible, .shoot = true}, &by_chord);
    const NearWalk field = WalkNearPair(
        parts.view, a, b,
        {.plausible = plausible, .heading = parts.paths.Heading(a, b), .shoot = true}, &by_field);
    // Both are surface paths, local geodesics near the shortest (a convex
    // polyhedron has several, of nearly the same length).
    for (const NearWalk* walk : {&chord, &field}) {
      if (!walk->path) continue;
      EXPECT_GE(walk->path->length, *exact * (1 - 1e-9)) << f << " " << g;
      EXPECT_LE(walk->path->length, *exact * 1.01) << f << " " << g;
    }
  }
  // On a sphere the chord, projected, is the great circle's direction: both
  // aims settle most pairs at the first shot.
  for (QueryScratch* scratch : {&by_chord, &by_field}) {
    EXPECT_GT(scratch->near_pair_stats().straight_at_shot[0], 20);
  }
}

}  // namespace
}  // namespace geodex::query
