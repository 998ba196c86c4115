#include "core/index/face_bvh.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include "core/index/face_bvh_testing.h"
#include "core/mesh/generators.h"
#include "gtest/gtest.h"

namespace geodex::index {
namespace {

using mesh::Mesh;
using mesh::Vec3;

using Flat = testing::FlatMesh;

TEST(BuildFaceBvhTest, EmptyMesh) {
  std::vector<BvhNode> nodes;
  std::vector<int32_t> leaf_faces;
  BuildFaceBvh({}, {}, &nodes, &leaf_faces);
  EXPECT_TRUE(nodes.empty());
  EXPECT_TRUE(leaf_faces.empty());
}

TEST(BuildFaceBvhTest, StructureAndBoxes) {
  const Mesh mesh = mesh::gen::Sphere(3, 1.0);
  const Flat flat(mesh);
  ASSERT_FALSE(flat.nodes.empty());
  std::vector<int> seen(mesh.num_faces(), 0);
  for (int32_t f : flat.leaf_faces) ++seen[f];
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), mesh.num_faces());
  std::vector<int> covered(flat.leaf_faces.size(), 0);
  for (size_t i = 0; i < flat.nodes.size(); ++i) {
    const BvhNode& n = flat.nodes[i];
    auto contains = [&](const Vec3& p) {
      for (int k = 0; k < 3; ++k) {
        if (!(n.lo[k] <= p[k] && p[k] <= n.hi[k])) return false;
      }
      return true;
    };
    if (n.count == 0) {
      EXPECT_GT(n.first, static_cast<int32_t>(i));
      ASSERT_LT(n.first + 1, static_cast<int32_t>(flat.nodes.size()));
      for (int32_t c : {n.first, n.first + 1}) {
        for (int k = 0; k < 3; ++k) {
          EXPECT_LE(n.lo[k], flat.nodes[c].lo[k]);
          EXPECT_GE(n.hi[k], flat.nodes[c].hi[k]);
        }
      }
    } else {
      EXPECT_LE(n.count, 4);
      EXPECT_GT(n.count, 0);
      for (int32_t j = n.first; j < n.first + n.count; ++j) {
        ++covered[j];
        for (int32_t v : mesh.face(flat.leaf_faces[j])) EXPECT_TRUE(contains(mesh.position(v)));
      }
    }
  }
  EXPECT_EQ(std::count(covered.begin(), covered.end(), 1), mesh.num_faces());
  // Median splits: depth about log2(faces / 4).
  EXPECT_LE(flat.nodes.size(), 2u * mesh.num_faces());
}

TEST(BuildFaceBvhTest, Deterministic) {
  const Mesh mesh = mesh::gen::Torus(20, 10, 1.0, 0.25);
  const Flat a(mesh), b(mesh);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  EXPECT_EQ(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(BvhNode)), 0);
  EXPECT_EQ(a.leaf_faces, b.leaf_faces);
}

}  // namespace
}  // namespace geodex::index
