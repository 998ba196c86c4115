#include "core/builder/mesh_arrays.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/geometry/sample_spacing.h"

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
  data->coarse_faces = record.coarse_faces;
  data->split_faces = record.split_faces;
  data->params.split_vertices = static_cast<uint32_t>(record.split_vertices);
  data->report = record.report + data->report;
}

absl::StatusOr<std::optional<CoarseSurface>> CoarseSurfaceOf(const mesh::Mesh& split,
                                                             const RepairRecord& record) {
  GEODEX_ASSIGN_OR_RETURN(
      const index::SplitView view,
      index::SplitView::Dense(record.coarse_faces, record.split_faces, split.num_faces(),
                              absl::StatusCode::kInvalidArgument));
  return CoarseSurfaceOf(split, view, record.split_vertices);
}

absl::StatusOr<std::optional<CoarseSurface>> CoarseSurfaceOf(const mesh::Mesh& split,
                                                             const index::SplitView& view,
                                                             int32_t split_vertices) {
  if (split_vertices == 0 && !view.split()) return std::nullopt;
  const int32_t coarse_vertices = split.num_vertices() - split_vertices;
  if (split_vertices <= 0 || coarse_vertices <= 0 || !view.split()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "the split (%d coarse faces, %d added vertices) is not of a mesh of %d vertices and %d "
        "faces",
        view.num_coarse_faces(), split_vertices, split.num_vertices(), split.num_faces()));
  }
  const int32_t num_coarse_faces = view.num_coarse_faces();
  std::vector<mesh::Vec3> positions(split.positions().begin(),
                                    split.positions().begin() + coarse_vertices);
  std::vector<mesh::Triangle> faces(num_coarse_faces);
  for (int32_t f = 0; f < num_coarse_faces; ++f) {
    const std::array<int32_t, 3> corners = view.CoarseFace(f);
    for (int32_t v : corners) {
      if (v < 0 || v >= coarse_vertices) {
        return absl::InvalidArgumentError(
            absl::StrFormat("a coarse face names vertex %d of %d", v, coarse_vertices));
      }
    }
    faces[f] = {corners[0], corners[1], corners[2]};
  }
  // The repaired input may keep faces of zero area.
  GEODEX_ASSIGN_OR_RETURN(
      mesh::Mesh coarse,
      mesh::Mesh::Create(std::move(positions), std::move(faces), split.name(),
                         mesh::MeshOptions{.allow_zero_area_faces = true}));
  std::vector<mesh::SurfacePoint> points(split.num_vertices());
  for (int32_t f = 0; f < split.num_faces(); ++f) {
    const index::SplitFaceRecord r = view.Piece(f);
    if (r.coarse_face < 0 || r.coarse_face >= num_coarse_faces) {
      return absl::InvalidArgumentError(
          absl::StrFormat("piece %d lies in coarse face %d of %d", f, r.coarse_face,
                          num_coarse_faces));
    }
    for (int i = 0; i < 3; ++i) {
      // The weights of a flat split are dyadic: float keeps them exactly.
      points[split.face(f)[i]] = {r.coarse_face, {r.weight[i][0], r.weight[i][1], r.weight[i][2]}};
    }
  }
  return std::optional<CoarseSurface>{CoarseSurface{std::move(coarse), std::move(points)}};
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
