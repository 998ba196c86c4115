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
#include "core/query/query_engine.h"

namespace geodex::query {

struct ExpMapOptions {
  // Vertices whose distance from the centre exceeds this are left out.
  double radius = 0;
  // θ = 0 along this direction, projected into the plane of the centre's
  // face; without it, along that face's first edge (corner 0 to corner 1).
  std::optional<mesh::Vec3> reference_direction;
  // How r is computed.
  DistanceOptions distance;
};

// One vertex of the map: polar (r, theta), theta in (-pi, pi], counter-
// clockwise about the centre face's normal, and (u, v) = r (cos, sin) theta.
struct ExpMapVertex {
  int32_t vertex = -1;
  double r = 0;
  double theta = 0;
  double u = 0;
  double v = 0;
};

// The map of every vertex within options.radius of `centre`, ascending by
// vertex id. Errors: as QueryEngine::Validate for the centre; InvalidArgument
// for a radius that is not finite and > 0, and for a reference direction that
// is not finite or is perpendicular to the centre's face.
absl::StatusOr<std::vector<ExpMapVertex>> ExpMap(const QueryEngine& engine,
                                                 const mesh::SurfacePoint& centre,
                                                 const ExpMapOptions& options,
                                                 QueryScratch* scratch = nullptr);

}  // namespace geodex::query
