#pragma once

// Distance fields from several sources (Xin, Ying & He 2012, §6.2): the
// distance from the nearest source to every vertex, as the minimum of O(1)
// answers: O(l n) for l sources and n vertices.
//
// Thread safety: a pure function of immutable data.

#include <span>

#include "core/query/engine/internal/o1/lifted_unfolding.h"
#include "core/query/engine/internal/o1/lifting.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

// The field of valid canonical `sources` over every vertex of `view`: the
// O(1) distance from each source (near pairs at least the straight-line
// distance), the smallest kept with the index of its source; +inf and -1 at
// vertices in no geodesic triangle.
DistanceField ApproximateField(const MeshView& view, const Lifting& lifting,
                               const LiftedUnfolding& unfolding,
                               std::span<const SurfacePoint> sources);

}  // namespace geodex::query
