#pragma once

// Test utility: a mesh flattened the way the index stores it (xyz per
// vertex, three vertex ids per face), with its face BVH. Shared by the BVH's
// and the point locator's tests.

#include <cstdint>
#include <vector>

#include "core/index/face_bvh.h"
#include "core/mesh/mesh.h"

namespace geodex::index::testing {

struct FlatMesh {
  std::vector<double> positions;
  std::vector<int32_t> faces;
  std::vector<BvhNode> nodes;
  std::vector<int32_t> leaf_faces;

  explicit FlatMesh(const mesh::Mesh& mesh) {
    for (const mesh::Vec3& p : mesh.positions()) {
      positions.insert(positions.end(), {p.x(), p.y(), p.z()});
    }
    for (const mesh::Triangle& f : mesh.faces()) faces.insert(faces.end(), f.begin(), f.end());
    BuildFaceBvh(positions, faces, &nodes, &leaf_faces);
  }
};

}  // namespace geodex::index::testing
