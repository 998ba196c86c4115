#pragma once

// Straightening of a surface path within the faces it crosses.
//
// A path traced down an approximate distance field wiggles: each step
// follows the local gradient, whose direction is only as good as the field.
// Between two points pinned at mesh vertices (or the path's ends) the path
// crosses a strip of faces; unfolded into the plane, the shortest path
// through that strip is found exactly by the funnel algorithm (Lee &
// Preparata 1984). It is a geodesic of the strip, so it is never longer than
// the input and, when the input runs in the right corridor, it is the exact
// geodesic. Points where the funnel wraps around a strip vertex are pinned at
// that vertex.
//
// Thread safety: reentrant.

#include <cstdint>
#include <span>
#include <vector>

#include "core/query/engine/mesh_view.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

// True when a point strictly inside the path is a mesh vertex: there the
// funnel of StraightenPath wrapped round the vertex.
bool WrapsRoundAVertex(const std::vector<PathPoint>& path);

// Returns the straightened path; the endpoints are kept exactly. Consecutive
// input points must share a face (as QueryEngine::Path produces); runs that
// do not are returned unchanged.
std::vector<PathPoint> StraightenPath(const MeshView& mesh, std::vector<PathPoint> path);

}  // namespace geodex::query
