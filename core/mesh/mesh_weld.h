#pragma once

// Internal to the STL and glTF readers (mesh_io_stl.cc, mesh_io_gltf.cc):
// welding the corners of a file that stores every triangle with its own
// three corners into shared vertices (ReadOptions in mesh_io.h). Not part of
// the public API; include core/mesh/mesh_io.h.

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"

namespace geodex::mesh::io_internal {

// The raw mesh of the triangles (corners[3t], corners[3t+1], corners[3t+2]),
// t in file order, corners welded as ReadOptions::weld_tolerance says: vertex
// ids in the order of their first corner, input_face[t] = t, raw.weld filled.
// The corners must be finite (the readers check). Errors: InvalidArgument
// for a bad tolerance, no triangles, or more triangles than a Mesh holds.
absl::StatusOr<RawMesh> WeldCorners(const std::vector<Vec3>& corners, const ReadOptions& options,
                                    const std::string& name);

}  // namespace geodex::mesh::io_internal
