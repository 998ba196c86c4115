#include "core/builder/mesh_arrays.h"

namespace geodex::builder {

std::vector<double> FlatPositions(const mesh::Mesh& mesh) {
  std::vector<double> positions;
  positions.reserve(3 * static_cast<size_t>(mesh.num_vertices()));
  for (const mesh::Vec3& p : mesh.positions()) {
    positions.insert(positions.end(), {p.x(), p.y(), p.z()});
  }
  return positions;
}

std::vector<int32_t> FlatFaces(const mesh::Mesh& mesh) {
  std::vector<int32_t> faces;
  faces.reserve(3 * static_cast<size_t>(mesh.num_faces()));
  for (const mesh::Triangle& f : mesh.faces()) faces.insert(faces.end(), f.begin(), f.end());
  return faces;
}

}  // namespace geodex::builder
