#include "core/index/coarse_surface.h"

#include <array>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::index {

absl::StatusOr<mesh::Mesh> CoarseMeshOf(std::span<const mesh::Vec3> positions,
                                        const SplitView& view, int32_t split_vertices,
                                        const std::string& name) {
  const int32_t num_vertices = static_cast<int32_t>(positions.size());
  const int32_t coarse_vertices = num_vertices - split_vertices;
  if (split_vertices <= 0 || coarse_vertices <= 0 || !view.split()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the split (%d coarse faces, %d added vertices) is not of a mesh of %d "
                        "vertices",
                        view.num_coarse_faces(), split_vertices, num_vertices));
  }
  const int32_t num_coarse_faces = view.num_coarse_faces();
  std::vector<mesh::Vec3> coarse_positions(positions.begin(), positions.begin() + coarse_vertices);
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
  return mesh::Mesh::Create(std::move(coarse_positions), std::move(faces), name,
                            mesh::MeshOptions{.allow_zero_area_faces = true});
}

absl::StatusOr<std::optional<CoarseSurface>> CoarseSurfaceOf(const mesh::Mesh& split,
                                                             const SplitView& view,
                                                             int32_t split_vertices) {
  if (split_vertices == 0 && !view.split()) return std::nullopt;
  GEODEX_ASSIGN_OR_RETURN(mesh::Mesh coarse,
                          CoarseMeshOf(split.positions(), view, split_vertices, split.name()));
  const int32_t num_coarse_faces = view.num_coarse_faces();
  std::vector<mesh::SurfacePoint> points(split.num_vertices());
  for (int32_t f = 0; f < split.num_faces(); ++f) {
    const SplitFaceRecord r = view.Piece(f);
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

}  // namespace geodex::index
