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
// The map takes its distances from the caller (the facade runs it through
// QueryEngine::WithDistances, which passes the engine's Distance and
// FieldWithin), so that it depends on the parts it reads and not on the
// engine that composes them. Distances below kRefineScale * L are taken
// from one exact propagation (SurfaceDistances::exact_within).
//
// Thread safety: a pure function of its inputs; the distance functions are
// called on the calling thread only.

#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"
#include "core/query/internal/surface_distances.h"
#include "core/query/query_types.h"

namespace geodex::query {

// The map of every vertex within options.radius of `centre`, ascending by
// vertex id. `centre` is valid, in the surface's ids. Errors: InvalidArgument
// for a radius that is not finite and > 0, and for a reference direction that
// is not finite or is perpendicular to the centre's face; those of the
// surface's distance functions.
absl::StatusOr<std::vector<ExpMapVertex>> ExpMap(const SurfaceDistances& surface,
                                                 const mesh::SurfacePoint& centre,
                                                 const ExpMapOptions& options);

}  // namespace geodex::query
