#pragma once

// The mesh a welding reader (STL, glTF: mesh_io.h) gives back for a mesh
// written by StlBytes or GlbBytes, for the tests of those formats.
// Test-only, header-only.

#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"

namespace geodex::mesh::testing {

// The mesh's faces and positions with the vertices renumbered in the order
// of their first corner (unreferenced ones left out), positions rounded to
// float32 when `round`: what welding a file of its corners reads, when no
// two vertices share a position.
inline RawMesh FirstCornerOrder(const Mesh& mesh, bool round) {
  RawMesh out;
  out.name = mesh.name();
  std::vector<int32_t> renumber(mesh.num_vertices(), kNone);
  for (int32_t f = 0; f < mesh.num_faces(); ++f) {
    Triangle u;
    for (int i = 0; i < 3; ++i) {
      const int32_t v = mesh.face(f)[i];
      if (renumber[v] == kNone) {
        renumber[v] = static_cast<int32_t>(out.positions.size());
        const Vec3& p = mesh.position(v);
        out.positions.push_back(round ? Vec3(p.cast<float>().cast<double>()) : p);
      }
      u[i] = renumber[v];
    }
    out.triangles.push_back(u);
    out.input_face.push_back(f);
  }
  return out;
}

}  // namespace geodex::mesh::testing
