#pragma once

// The discrete exponential map (Xin, Ying & He 2012, §6.4): geodesic polar
// coordinates round a centre point, for texture decals and local charts.
//
// r is the engine's distance from the centre (Distance with the caller's
// DistanceOptions: near pairs refined as usual). θ is the direction in which
// the geodesic to a vertex leaves the centre, propagated outwards in order of
// r as in geodesic polar coordinates (Melvær & Reimers 2012): a vertex w is
// unfolded into the centre's tangent plane across each face (w, a, b) whose
// other corners already have coordinates, and the straight ray from the
// centre to the unfolded w tells where the geodesic crosses a-b; when it
// misses the edge, the geodesic bends round a (or b) and w takes that
// vertex's angle. Of the faces, the one giving the shortest path is used, as
// a propagation of distances would. On a developable surface the unfolding is
// exact, so the map is an isometry wherever the distances are exact; a cone
// point at the centre has its angles scaled to a full turn.
//
// Only the vertices within the radius and one ring round them are visited:
// the cost grows with the vertices inside the radius, not with the mesh.
//
// Thread safety: a pure function of an immutable engine; pass one
// QueryScratch per thread.

#include <cstdint>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"
#include "core/query/internal/query_engine.h"

namespace geodex::query {

// The map of every vertex within options.radius of `centre`, ascending by
// vertex id. `centre` is valid, in the engine's ids. Errors: InvalidArgument
// for a radius that is not finite and > 0, and for a reference direction that
// is not finite or is perpendicular to the centre's face.
absl::StatusOr<std::vector<ExpMapVertex>> ExpMap(const QueryEngine& engine,
                                                 const mesh::SurfacePoint& centre,
                                                 const ExpMapOptions& options,
                                                 QueryScratch* scratch = nullptr);

}  // namespace geodex::query
