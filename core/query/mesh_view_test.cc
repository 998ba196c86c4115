#include "core/query/mesh_view.h"

#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

using ::testing::ElementsAre;
using ::testing::UnorderedElementsAre;

// Twins of the half-edges 3 f + i (corner i -> i+1): the reversed edge, or -1.
std::vector<int32_t> Twins(const std::vector<int32_t>& faces) {
  std::vector<int32_t> twins(faces.size(), -1);
  for (size_t h = 0; h < faces.size(); ++h) {
    const int32_t a = faces[h], b = faces[h - h % 3 + (h % 3 + 1) % 3];
    for (size_t g = 0; g < faces.size(); ++g) {
      if (faces[g] == b && faces[g - g % 3 + (g % 3 + 1) % 3] == a) twins[h] = g;
    }
  }
  return twins;
}

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

}  // namespace
}  // namespace geodex::query
