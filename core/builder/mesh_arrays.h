#pragma once

// The mesh as the index stores it (core/index/index_format.h): 3 doubles per
// vertex and 3 vertex ids per face, in mesh order. The builder hashes these
// arrays (index::MeshHash) and writes them into the index.

#include <cstdint>
#include <string>
#include <vector>

#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_repair.h"

namespace geodex::builder {

std::vector<double> FlatPositions(const mesh::Mesh& mesh);
std::vector<int32_t> FlatFaces(const mesh::Mesh& mesh);

// What the repair of an index's mesh did (core/mesh/mesh_repair.h), as the
// index records it: its input-id sections (format 1.2: input faces and vertex
// copies, empty for identity maps) and the report's mesh_* lines.
struct RepairRecord {
  std::vector<index::InputFaceRecord> input_faces;
  std::vector<int32_t> vertex_copies;
  std::string report;
};
RepairRecord RecordRepair(const mesh::RepairedMesh& repaired);

// Puts `record` into the index data of the repaired mesh: the sections, and
// the report lines first in its report. Call it once.
void AddRepair(const RepairRecord& record, index::IndexData* data);

}  // namespace geodex::builder
