#pragma once

// The mesh the builder samples: the repaired input, its long edges split for
// the sample count, and the record of both that the index keeps (its input-id
// sections and its report's mesh_* lines).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/coarse_surface.h"
#include "core/index/index.h"
#include "core/mesh/long_edge_split.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_repair.h"

namespace geodex::builder {

// What the repair of an index's mesh did (core/mesh/mesh_repair.h), and the
// long-edge split after it, as the index records them: its input-id sections
// (format 1.2: input faces and vertex copies, empty for identity maps; 2.0:
// the coarse faces and the pieces, empty without the split) and the
// report's mesh_* lines.
struct RepairRecord {
  std::vector<index::InputFaceRecord> input_faces;
  std::vector<int32_t> vertex_copies;
  std::vector<int32_t> coarse_faces;
  std::vector<index::SplitFaceRecord> split_faces;
  int32_t split_vertices = 0;
  std::string report;
};
RepairRecord RecordRepair(const mesh::RepairedMesh& repaired);

// Puts `record` into the index data of the (repaired, refined) mesh: the
// sections, and the report lines first in its report. Call it once.
void AddRepair(const RepairRecord& record, index::IndexData* data);

// Samples are mesh vertices, so a geodesic triangle is no smaller than the
// mesh edges it spans: on a coarse mesh the error stops falling with m once
// the sample spacing L(m) = sqrt(2 A / (sqrt(3) m)) reaches the long edges.
// The builder splits flat (core/mesh/long_edge_split.h) every edge longer
// than this share of L(m), so that a vertex lies within about L/4 of every
// point and farthest-point sampling can place samples L apart anywhere.
inline constexpr double kMaxEdgeOverScaleLength = 0.5;

// The long-edge split the builder applies before sampling `num_samples` samples:
// SplitLongEdges at kMaxEdgeOverScaleLength * L(num_samples), adding at most
// 4 vertices per input vertex plus 16 per sample. A mesh with no longer edge
// comes back unchanged (new_vertices == 0). Errors: SplitLongEdges's.
absl::StatusOr<mesh::LongEdgeSplit> SplitForSamples(const mesh::Mesh& mesh, int32_t num_samples);

// Records `split` of `coarse` (the mesh RecordRepair's record is of)
// into `record`: the sections and a mesh_split report line. Nothing for
// a split that added no vertex.
void AddSplitFaces(const mesh::Mesh& coarse, const mesh::LongEdgeSplit& split,
                   RepairRecord* record);

// The mesh the builder samples for `num_samples` samples and the record of
// how it came from the input: `coarse` (the repaired input, whose repair is
// `repair`), split by SplitForSamples when `split_long_edges`. The index built from
// `mesh` takes AddRepair(record).
struct PreparedMesh {
  mesh::Mesh mesh;
  RepairRecord record;
};
absl::StatusOr<PreparedMesh> PrepareMesh(const mesh::Mesh& coarse, RepairRecord repair,
                                         int32_t num_samples, bool split_long_edges);

// The coarse surface (index::CoarseSurfaceOf) of `split`, the mesh of a
// PreparedMesh whose record is `record`.
absl::StatusOr<std::optional<index::CoarseSurface>> CoarseSurfaceOf(const mesh::Mesh& split,
                                                                    const RepairRecord& record);

// The input file's id of each vertex of `prepared.mesh`: its own below the
// repair's copies, the vertex a copy stands for, mesh::kNone for a midpoint
// of the split (BuildOptions::input_vertex_ids, for refusal messages).
std::vector<int32_t> InputVertexIds(const PreparedMesh& prepared);

}  // namespace geodex::builder
