#include "core/query/engine/mesh_view.h"

#include <array>
#include <vector>

#include "core/query/engine/mesh_view_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

using ::testing::ElementsAre;
using ::testing::UnorderedElementsAre;

using testing::Twins;

TEST(MeshViewTest, FanAtABoundaryVertexWalksBothWays) {
  // A unit square split along its diagonal 0-2.
  const std::vector<double> positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<int32_t> faces = {0, 1, 2, 0, 2, 3};
  const std::vector<int32_t> twins = Twins(faces);
  const MeshView view{positions, faces, twins};
  EXPECT_EQ(view.Position(2), mesh::Vec3(1, 1, 0));
  EXPECT_EQ(view.Vertex(1, 2), 3);
  EXPECT_EQ(view.Corner(1, 2), 1);
  EXPECT_EQ(view.Corner(1, 1), -1);
  EXPECT_EQ(view.Turn(0, 0, 0), -1);  // the edge 0-1 is on the boundary
  EXPECT_EQ(view.Turn(0, 0, 1), 1);   // across the diagonal
  EXPECT_EQ(view.Turn(0, 3, 0), -1);  // face 0 does not hold vertex 3
  std::vector<int32_t> fan;
  view.FacesAround(0, 0, &fan);
  EXPECT_THAT(fan, ElementsAre(0, 1));
  fan.clear();
  view.FacesAround(0, 1, &fan);
  EXPECT_THAT(fan, ElementsAre(1, 0));
  fan.clear();
  view.FacesAround(1, 0, &fan);
  EXPECT_THAT(fan, ElementsAre(0));
}

TEST(MeshViewTest, FanAtAnInteriorVertexClosesOnce) {
  // A tetrahedron: every vertex is in three faces.
  const std::vector<double> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::vector<int32_t> faces = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  const std::vector<int32_t> twins = Twins(faces);
  const MeshView view{positions, faces, twins};
  for (int32_t v = 0; v < 4; ++v) {
    for (int32_t f = 0; f < 4; ++f) {
      if (view.Corner(f, v) < 0) continue;
      std::vector<int32_t> fan;
      view.FacesAround(v, f, &fan);
      ASSERT_EQ(fan.size(), 3u) << "vertex " << v << " face " << f;
      EXPECT_EQ(fan[0], f);
    }
  }
  std::vector<int32_t> fan;
  view.FacesAround(0, 0, &fan);
  EXPECT_THAT(fan, UnorderedElementsAre(0, 1, 2));
}

TEST(MeshViewTest, EdgePointsAreCanonicalInTheFaceOfLowerId) {
  // The unit square: the diagonal 0-2 is shared by faces 0 (0, 1, 2) and 1
  // (0, 2, 3).
  const std::vector<double> positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<int32_t> faces = {0, 1, 2, 0, 2, 3};
  const std::vector<int32_t> twins = Twins(faces);
  const MeshView view{positions, faces, twins};
  // The diagonal's midpoint described in face 1 comes back in face 0.
  const mesh::SurfacePoint c = view.Canonical({1, {0.5, 0.5, 0}});
  EXPECT_EQ(c.face, 0);
  EXPECT_THAT(c.w, ElementsAre(0.5, 0, 0.5));
  EXPECT_EQ(view.PositionOf(c), mesh::Vec3(0.5, 0.5, 0));
  // Weights are clamped and renormalised; a point on a boundary edge keeps
  // its face.
  const mesh::SurfacePoint inside = view.Canonical({1, {-1e-9, 0.5, 0.5 + 1e-9}});
  EXPECT_EQ(inside.face, 1);
  EXPECT_DOUBLE_EQ(inside.w[0] + inside.w[1] + inside.w[2], 1);
  EXPECT_EQ(inside.w[0], 0);
  // A vertex point goes to the lowest face round its vertex.
  const mesh::SurfacePoint v = view.InLowestFaceIfVertex({1, {0, 0, 1}});  // vertex 3
  EXPECT_EQ(v.face, 1);  // only face 1 holds vertex 3
  const mesh::SurfacePoint v0 = view.InLowestFaceIfVertex({1, {1, 0, 0}});  // vertex 0
  EXPECT_EQ(v0.face, 0);
  EXPECT_THAT(v0.w, ElementsAre(1, 0, 0));
  EXPECT_DOUBLE_EQ(view.Area(), 1);
}

TEST(MeshViewTest, DescentLeavesByTheFirstWeightToReachZero) {
  double t;
  // Moving from the centroid towards corner 0: corners 1 and 2 lose weight
  // equally; the first (corner 1) is reported, after a step of 1/3 / 0.5.
  EXPECT_EQ(DescentExit({1, -0.5, -0.5}, {1.0 / 3, 1.0 / 3, 1.0 / 3}, &t), 1);
  EXPECT_DOUBLE_EQ(t, 2.0 / 3);
  EXPECT_EQ(DescentExit({-1, 0.25, 0.75}, {0.5, 0.25, 0.25}, &t), 0);
  EXPECT_DOUBLE_EQ(t, 0.5);
  // No weight decreases: no exit.
  EXPECT_EQ(DescentExit({0, 0, 0}, {0.2, 0.3, 0.5}, &t), -1);
}

TEST(MeshViewTest, AcrossEdgeKeepsThePointOnTheSharedEdge) {
  const std::vector<double> positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<int32_t> faces = {0, 1, 2, 0, 2, 3};
  const std::vector<int32_t> twins = Twins(faces);
  const MeshView view{positions, faces, twins};
  // In face 0 the diagonal is the edge opposite corner 1 (vertices 2 -> 0).
  const std::array<double, 3> w = {0.25, 0, 0.75};
  const int32_t g = twins[3 * 0 + 2];  // the half-edge 2 -> 0 of face 0, seen from face 1
  ASSERT_EQ(g / 3, 1);
  const std::array<double, 3> across = AcrossEdge(g, 1, w);
  const mesh::SurfacePoint here{0, w}, there{1, across};
  EXPECT_EQ(view.PositionOf(here), view.PositionOf(there));
  EXPECT_DOUBLE_EQ(across[0] + across[1] + across[2], 1);
}

}  // namespace
}  // namespace geodex::query
