#pragma once

// The surface an index's mesh was before its long edges were split
// (core/index/split_view.h reads the split's sections). The builder runs its
// exact propagations there, and the calibration its reference distances.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/split_view.h"
#include "core/mesh/mesh.h"

namespace geodex::index {

// The surface before the long-edge split, where an exact propagation is
// several times cheaper than on the split mesh (it has a fraction of the
// vertices) and gives the same distances: the split is flat, so its
// midpoints are points of the coarse faces.
struct CoarseSurface {
  mesh::Mesh mesh;  // the coarse faces over the split mesh's first vertices
  // Per vertex of the split mesh, the same point of `mesh` (face kNone for
  // an unreferenced vertex).
  std::vector<mesh::SurfacePoint> points;
};
// The coarse faces alone over the first of `positions` (a split mesh's
// vertices, the `split_vertices` added ones last): the mesh an exact
// propagation between two points needs. Errors: InvalidArgument when the
// split is not of these vertices.
absl::StatusOr<mesh::Mesh> CoarseMeshOf(std::span<const mesh::Vec3> positions,
                                        const SplitView& view, int32_t split_vertices,
                                        const std::string& name);

// The coarse surface of `split`, a mesh split as `view` says (a builder's
// record, or an index's sections) after `split_vertices` added vertices;
// nullopt when nothing was split. Errors: InvalidArgument when the split is
// not of `split`.
absl::StatusOr<std::optional<CoarseSurface>> CoarseSurfaceOf(const mesh::Mesh& split,
                                                             const SplitView& view,
                                                             int32_t split_vertices);

}  // namespace geodex::index
