#pragma once

// The mesh as the index stores it (core/index/index_format.h): 3 doubles per
// vertex and 3 vertex ids per face, in mesh order. The builder hashes these
// arrays (index::MeshHash) and writes them into the index.

#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"

namespace geodex::builder {

std::vector<double> FlatPositions(const mesh::Mesh& mesh);
std::vector<int32_t> FlatFaces(const mesh::Mesh& mesh);

}  // namespace geodex::builder
