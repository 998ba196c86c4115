#pragma once

// The sections of an index that a reader can derive from others (format
// 6.0, index_format.h): the twins from the faces, the face BVH from the
// positions and faces (face_bvh.h), and the vertex records' corners from
// their geodesic triangles. The writer leaves the twins and the BVH out
// when these derivations give them back as they are, and the reader
// derives them at load; so both must run the same code. Internal to
// core/index.
//
// Thread safety: pure functions of their inputs.

#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/index/index_format.h"

namespace geodex::index::internal {

// The twin of every half-edge (3 f + k, from corner k to corner k + 1 of face
// f): the one half-edge of another face that runs the other way along the
// same edge, or -1 on the boundary. The pairing core/mesh/mesh.h makes.
// Errors (`code`): an edge of more than two faces, or of two that run it the
// same way (such a mesh has no twins; the builder never writes one).
absl::StatusOr<std::vector<int32_t>> DeriveTwins(std::span<const int32_t> faces,
                                                 absl::StatusCode code);

// The records of 1.x-5.x without their corners (which CheckContents checks
// are their triangle's).
std::vector<VertexRecord> WithoutCorners(std::span<const VertexRecordWithCorners> records);
// The records of 1.x-5.x: each with its triangle's corners copied in.
// Triangles must be in range (CheckContents).
std::vector<VertexRecordWithCorners> WithCorners(std::span<const VertexRecord> records,
                                                 std::span<const GeodesicTriangle> triangles);

}  // namespace geodex::index::internal
