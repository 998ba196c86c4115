#include "core/query/engine/internal/paths/strip_funnel.h"

#include <cmath>
#include <numbers>
#include <vector>

#include "core/query/engine/mesh_view_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

using geometry::Vec2;
using ::testing::ElementsAre;

using testing::Twins;

// A mesh held by its arrays, with its view.
struct TestMesh {
  TestMesh(std::vector<double> p, std::vector<int32_t> f)
      : positions(std::move(p)), faces(std::move(f)), twins(Twins(faces)) {}
  std::vector<double> positions;
  std::vector<int32_t> faces;
  std::vector<int32_t> twins;
  MeshView view() const { return {positions, faces, twins}; }
};

// A unit square (z = 0) and, folded up by a right angle along x = 1, a second
// one (x = 1): developable, it unfolds to the rectangle [0, 2] x [0, 1].
TestMesh FoldedSheet() {
  return TestMesh({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 0, 1, 1, 1, 1},
                  {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2});
}

// An L of three unit squares in the plane z = 0 (the square [1, 2] x [1, 2]
// missing): vertex 3 j + i at (i, j); vertex 4, at (1, 1), is the reflex
// corner. Each square (a, b, c, d) counter-clockwise from its lower left is
// split into (a, b, c) and (a, c, d).
TestMesh LShape() {
  std::vector<double> positions;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) positions.insert(positions.end(), {double(i), double(j), 0});
  }
  return TestMesh(positions, {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 3, 4, 7, 3, 7, 6});
}

// A strip of faces unfolded (consecutive faces share an edge), its portals
// named left and right going out of each face.
UnfoldedStrip Unfold(const MeshView& view, const std::vector<int32_t>& strip,
                     const mesh::SurfacePoint& from, const mesh::SurfacePoint& to) {
  UnfoldedStrip out;
  EXPECT_TRUE(UnfoldStrip(view, strip, from, to, 0, &out)) << "two faces share no edge";
  return out;
}

TEST(StripFunnelTest, LayOutFaceKeepsTheEdgeLengths) {
  const TestMesh m({0.3, -1, 2, 2.3, 0.5, 1, -0.4, 1.2, 2.5}, {0, 1, 2});
  const MeshView view = m.view();
  const FlatFace flat = LayOutFace(view, 0);
  EXPECT_THAT(flat.vertices, ElementsAre(0, 1, 2));
  EXPECT_EQ(flat.corners[0], Vec2(0, 0));
  EXPECT_EQ(flat.corners[1].y(), 0);
  EXPECT_GT(flat.corners[1].x(), 0);
  EXPECT_GT(flat.corners[2].y(), 0);  // counter-clockwise
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    EXPECT_NEAR((flat.corners[i] - flat.corners[j]).norm(),
                (view.Position(i) - view.Position(j)).norm(), 1e-14);
  }
}

TEST(StripFunnelTest, UnfoldAcrossAFoldFlattensIt) {
  const TestMesh m = FoldedSheet();
  const MeshView view = m.view();
  // Face 0 (0, 1, 2) as laid out is the square's lower right half; face 2
  // (1, 4, 5) across the fold's edge 1-2 unfolds onto x in [1, 2].
  const FlatFace first = LayOutFace(view, 0);
  EXPECT_EQ(first.At(2), Vec2(1, 1));
  const FlatFace across = UnfoldAcross(view, first, 3, 1, 2);
  EXPECT_THAT(across.vertices, ElementsAre(1, 5, 2));
  EXPECT_EQ(across.At(1), Vec2(1, 0));
  EXPECT_EQ(across.At(2), Vec2(1, 1));
  EXPECT_NEAR((across.At(5) - Vec2(2, 1)).norm(), 0, 1e-15);
  EXPECT_EQ(across.Opposite(1, 2), 5);
  // A point is its weighted corners.
  const Vec2 p = LocateInFlat(view, across, {3, {0.5, 0.25, 0.25}}, 0);
  EXPECT_NEAR((p - Vec2(1.25, 0.5)).norm(), 0, 1e-15);
}

TEST(StripFunnelTest, AFlatStripIsOneStraightSegment) {
  const TestMesh m = FoldedSheet();
  const MeshView view = m.view();
  // (0.1, 0.8) in face 1, and (1, 0.3, 0.9), unfolded to (1.9, 0.3), in
  // face 2.
  const mesh::SurfacePoint from{1, {0.2, 0.1, 0.7}}, to{2, {0.1, 0.6, 0.3}};
  const double want = std::hypot(1.8, 0.5);
  const UnfoldedStrip strip = Unfold(view, {1, 0, 3, 2}, from, to);
  ASSERT_EQ(strip.portals.size(), 3);
  const std::optional<double> straight = StraightLength(strip.start, strip.portals, strip.end);
  ASSERT_TRUE(straight.has_value());
  EXPECT_NEAR(*straight, want, 1e-14);
  const FunnelPath path = Funnel(strip.start, strip.portals, strip.end);
  EXPECT_TRUE(path.bends.empty());
  EXPECT_NEAR(path.length, want, 1e-14);
}

TEST(StripFunnelTest, AStripRoundAReflexCornerBendsAtItsVertex) {
  const TestMesh m = LShape();
  const MeshView view = m.view();
  // From (1.8, 0.9) round the corner (1, 1) to (0.9, 1.8): the segment
  // between them leaves the L.
  const mesh::SurfacePoint from{3, {0.1, 0.8, 0.1}}, to{4, {0.1, 0.1, 0.8}};
  const double want = 2 * std::hypot(0.8, 0.1);
  const UnfoldedStrip strip = Unfold(view, {3, 0, 1, 4}, from, to);
  ASSERT_EQ(strip.portals.size(), 3);
  EXPECT_FALSE(StraightLength(strip.start, strip.portals, strip.end).has_value());
  const FunnelPath path = Funnel(strip.start, strip.portals, strip.end);
  EXPECT_NEAR(path.length, want, 1e-14);
  ASSERT_EQ(path.bends.size(), 1);
  const FunnelBend bend = path.bends[0];
  EXPECT_EQ(strip.portals[bend.portal].vertices[bend.side], 4);
}

TEST(StripFunnelTest, BendsAtThePortalEndsItMustGoRound) {
  // Portals across the x axis at x = 1, 2, 3, left end above; the one at
  // x = 2 is blocked below y = 0 (its right end).
  const std::vector<Portal> portals = {{{Vec2(1, 5), Vec2(1, -5)}, {10, 11}},
                                       {{Vec2(2, 5), Vec2(2, 0)}, {12, 13}},
                                       {{Vec2(3, 5), Vec2(3, -5)}, {14, 15}}};
  const FunnelPath below = Funnel(Vec2(0, -2), portals, Vec2(4, -2));
  EXPECT_DOUBLE_EQ(below.length, 2 * std::sqrt(8.0));
  ASSERT_EQ(below.bends.size(), 1);
  EXPECT_EQ(below.bends[0].portal, 1);
  EXPECT_EQ(below.bends[0].side, Portal::kRight);
  EXPECT_FALSE(StraightLength(Vec2(0, -2), portals, Vec2(4, -2)).has_value());
  // Above the block, the path is straight.
  const FunnelPath above = Funnel(Vec2(0, 1), portals, Vec2(4, 3));
  EXPECT_TRUE(above.bends.empty());
  EXPECT_DOUBLE_EQ(above.length, std::sqrt(20.0));
  EXPECT_DOUBLE_EQ(*StraightLength(Vec2(0, 1), portals, Vec2(4, 3)), std::sqrt(20.0));
  // Blocked above at x = 1 and below at x = 3: it zigzags round both.
  const std::vector<Portal> zigzag = {{{Vec2(1, 0), Vec2(1, -5)}, {10, 11}},
                                      {{Vec2(2, 5), Vec2(2, -5)}, {12, 13}},
                                      {{Vec2(3, 5), Vec2(3, 0)}, {14, 15}}};
  const FunnelPath twice = Funnel(Vec2(0, 1), zigzag, Vec2(4, -1));
  EXPECT_DOUBLE_EQ(twice.length, std::sqrt(2.0) + 2 + std::sqrt(2.0));
  ASSERT_EQ(twice.bends.size(), 2);
  EXPECT_EQ(zigzag[twice.bends[0].portal].vertices[twice.bends[0].side], 10);
  EXPECT_EQ(zigzag[twice.bends[1].portal].vertices[twice.bends[1].side], 15);
}

TEST(StripFunnelTest, DegeneratePortals) {
  // No portal: the segment.
  EXPECT_DOUBLE_EQ(Funnel(Vec2(0, 0), {}, Vec2(3, 4)).length, 5);
  EXPECT_DOUBLE_EQ(*StraightLength(Vec2(0, 0), {}, Vec2(3, 4)), 5);
  // A portal of zero width: the path goes through its one point, straight
  // when it lies on the segment, bent there otherwise.
  const std::vector<Portal> on = {{{Vec2(2, 0), Vec2(2, 0)}, {0, 0}}};
  EXPECT_DOUBLE_EQ(Funnel(Vec2(0, 0), on, Vec2(4, 0)).length, 4);
  EXPECT_DOUBLE_EQ(*StraightLength(Vec2(0, 0), on, Vec2(4, 0)), 4);
  const std::vector<Portal> off = {{{Vec2(2, 1), Vec2(2, 1)}, {0, 0}}};
  const FunnelPath bent = Funnel(Vec2(0, 0), off, Vec2(4, 0));
  EXPECT_DOUBLE_EQ(bent.length, 2 * std::sqrt(5.0));
  EXPECT_EQ(bent.bends.size(), 1);
  EXPECT_FALSE(StraightLength(Vec2(0, 0), off, Vec2(4, 0)).has_value());
  // The start at a portal's end (a path from a vertex).
  const std::vector<Portal> from_end = {{{Vec2(0, 1), Vec2(0, 0)}, {0, 1}},
                                        {{Vec2(1, 1), Vec2(1, -1)}, {2, 3}}};
  const FunnelPath straight = Funnel(Vec2(0, 0), from_end, Vec2(2, 1));
  EXPECT_TRUE(straight.bends.empty());
  EXPECT_DOUBLE_EQ(straight.length, std::sqrt(5.0));
}

TEST(StripFunnelTest, WalksRoundAVertexAndItsAngles) {
  const TestMesh m = LShape();
  const MeshView view = m.view();
  // Round the reflex corner 4 from face 3 to face 4: through the lower
  // left square one way, the boundary the other.
  absl::InlinedVector<int32_t, 16> between;
  int reached = 0;
  for (int dir = 0; dir < 2; ++dir) {
    if (FacesBetween(view, 4, 3, 4, dir, &between)) {
      ++reached;
      EXPECT_THAT(between, ElementsAre(0, 1));
    }
  }
  EXPECT_EQ(reached, 1);
  double total = 0;
  for (int32_t f : {3, 0, 1, 4}) total += CornerAngle(view, f, 4);
  EXPECT_NEAR(total, 1.5 * std::numbers::pi, 1e-15);
  EXPECT_NEAR(CornerAngle(view, 0, 4), std::numbers::pi / 4, 1e-15);
  EXPECT_NEAR(CornerAngle(view, 4, 4), std::numbers::pi / 2, 1e-15);
}

TEST(StripFunnelTest, FaceHoldsThePointsOfItsClosure) {
  const TestMesh m = LShape();
  const MeshView view = m.view();
  const mesh::SurfacePoint inside{0, {0.2, 0.3, 0.5}}, on_edge{0, {0.5, 0, 0.5}},
      vertex{0, {0, 0, 1}}, almost{0, {0.5, 1e-13, 0.5}};
  EXPECT_TRUE(FaceHolds(view, 0, inside));
  EXPECT_FALSE(FaceHolds(view, 1, inside));
  EXPECT_TRUE(FaceHolds(view, 1, on_edge));  // the edge 0-4
  EXPECT_TRUE(FaceHolds(view, 1, almost));   // within 1e-12 of it
  EXPECT_FALSE(FaceHolds(view, 3, on_edge));
  for (int32_t f : {0, 1, 3, 4}) EXPECT_TRUE(FaceHolds(view, f, vertex));
  EXPECT_FALSE(FaceHolds(view, 2, vertex));
}

}  // namespace
}  // namespace geodex::query
