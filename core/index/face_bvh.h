#pragma once

// The face BVH of the index (SectionId::kFaceBvh, kBvhFaces): an axis-aligned
// bounding-box hierarchy over the faces of the mesh. The builder fills it;
// the query engine's point locator (core/query/engine/internal/locate/point_locator.h) walks it in
// place.
//
// Thread safety: BuildFaceBvh is a pure function of its inputs.

#include <cstdint>
#include <span>
#include <vector>

#include "core/index/index_format.h"

namespace geodex::index {

// BuildFaceBvh fills `nodes` and `leaf_faces` with the BVH over faces
// (positions: 3 doubles per vertex, faces: 3 ids per face). Boxes are rounded
// outwards to float so they always contain their faces. Deterministic: the
// result is a function of the inputs alone. `nodes[0]` is the root; both
// outputs are empty for an empty mesh.
void BuildFaceBvh(std::span<const double> positions, std::span<const int32_t> faces,
                  std::vector<BvhNode>* nodes, std::vector<int32_t>* leaf_faces);

}  // namespace geodex::index
