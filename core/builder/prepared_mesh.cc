#include "core/builder/prepared_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"
#include "core/builder/mesh_arrays.h"
#include "core/common/status_macros.h"
#include "core/geometry/sample_spacing.h"

namespace geodex::builder {

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
  data->coarse_faces = record.coarse_faces;
  data->split_faces = record.split_faces;
  data->params.split_vertices = static_cast<uint32_t>(record.split_vertices);
  data->report = record.report + data->report;
}

absl::StatusOr<std::optional<index::CoarseSurface>> CoarseSurfaceOf(const mesh::Mesh& split,
                                                                    const RepairRecord& record) {
  GEODEX_ASSIGN_OR_RETURN(
      const index::SplitView view,
      index::SplitView::Dense(record.coarse_faces, record.split_faces, split.num_faces(),
                              absl::StatusCode::kInvalidArgument));
  return index::CoarseSurfaceOf(split, view, record.split_vertices);
}

absl::StatusOr<mesh::LongEdgeSplit> SplitForSamples(const mesh::Mesh& mesh, int32_t num_samples) {
  const double scale_length = geometry::SampleSpacing(mesh.TotalArea(), num_samples);
  const int64_t cap = 4 * int64_t{mesh.num_vertices()} + 16 * int64_t{std::max(num_samples, 0)};
  double max_edge = kMaxEdgeOverScaleLength * scale_length;
  // A surface of zero area has no scale: leave it as it is.
  if (!(max_edge > 0) || !std::isfinite(max_edge)) max_edge = std::numeric_limits<double>::max();
  return mesh::SplitLongEdges(mesh, max_edge,
                              static_cast<int32_t>(std::min<int64_t>(cap, 1 << 30)));
}

void AddSplitFaces(const mesh::Mesh& coarse, const mesh::LongEdgeSplit& split,
                   RepairRecord* record) {
  if (split.new_vertices == 0) return;
  record->coarse_faces = FlatFaces(coarse);
  record->split_faces.resize(split.parent.size());
  for (size_t f = 0; f < split.parent.size(); ++f) {
    index::SplitFaceRecord& r = record->split_faces[f];
    r.coarse_face = split.parent[f];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) r.weight[i][j] = static_cast<float>(split.weights[f][i][j]);
    }
  }
  record->split_vertices = split.new_vertices;
  record->report += absl::StrFormat(
      "mesh_split = %d midpoints added, %d faces became %d (long edges split flat)\n",
      split.new_vertices, coarse.num_faces(), split.mesh.num_faces());
}

absl::StatusOr<PreparedMesh> PrepareMesh(const mesh::Mesh& coarse, RepairRecord repair,
                                         int32_t num_samples, bool split_long_edges) {
  if (!split_long_edges) return PreparedMesh{coarse, std::move(repair)};
  absl::StatusOr<mesh::LongEdgeSplit> split = SplitForSamples(coarse, num_samples);
  if (!split.ok()) return split.status();
  if (split->new_vertices == 0) return PreparedMesh{coarse, std::move(repair)};
  AddSplitFaces(coarse, *split, &repair);
  return PreparedMesh{std::move(split->mesh), std::move(repair)};
}

std::vector<int32_t> InputVertexIds(const PreparedMesh& prepared) {
  const RepairRecord& record = prepared.record;
  const int32_t nv = prepared.mesh.num_vertices();
  const int32_t coarse = nv - record.split_vertices;
  const int32_t input = coarse - static_cast<int32_t>(record.vertex_copies.size());
  std::vector<int32_t> ids(nv, mesh::kNone);
  for (int32_t v = 0; v < coarse; ++v) ids[v] = v < input ? v : record.vertex_copies[v - input];
  return ids;
}

}  // namespace geodex::builder
