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

RepairRecord RecordRepair(const mesh::RepairedMesh& repaired) {
  RepairRecord out;
  for (const mesh::InputFace& f : repaired.maps.faces) {
    index::InputFaceRecord r;
    r.face = f.face;
    for (int i = 0; i < 3; ++i) r.corner[i] = f.corner[i];
    r.flags = (f.dropped ? index::kInputFaceDropped : 0) |
              (f.reoriented ? index::kInputFaceReoriented : 0);
    out.input_faces.push_back(r);
  }
  out.vertex_copies = repaired.maps.vertex_copies;
  out.report = repaired.report.ToText();
  return out;
}

void AddRepair(const RepairRecord& record, index::IndexData* data) {
  data->input_faces = record.input_faces;
  data->vertex_copies = record.vertex_copies;
  data->report = record.report + data->report;
}

}  // namespace geodex::builder
