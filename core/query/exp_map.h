#pragma once

// The discrete exponential map (Xin, Ying & He 2012, §6.4): geodesic polar
// coordinates round a centre point, for texture decals and local charts, in
// the ids of the mesh file the index was built from. A query of its own over
// InputQueries, which reads its centre and lends it the engine's distances
// and the input ids: the options, the answer and the call are all here, and
// the work is in exp_map.cc.
//
// r is the engine's distance from the centre (Distance with the options'
// DistanceOptions: near pairs refined as usual). θ is the direction in which
// the geodesic to a vertex leaves the centre, propagated outwards in order
// of r as in geodesic polar coordinates (Melvær & Reimers 2012). On a
// developable surface the map is an isometry wherever the distances are
// exact; a cone point at the centre has its angles scaled to a full turn.
// Only the vertices within the radius and one ring round them are visited:
// the cost grows with the vertices inside the radius, not with the mesh.
//
//   query::EnginePoints centre;
//   GEODEX_RETURN_IF_ERROR(queries->Read(input_centre, query::Named("center"), &centre));
//   GEODEX_ASSIGN_OR_RETURN(auto map, query::ExpMap(*queries, centre, 0, {.radius = 1.5}));
//
// Thread safety: as InputQueries' const methods; scratch is the caller's.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

class EnginePoints;
class InputQueries;
class QueryScratch;

struct ExpMapOptions {
  // Vertices whose distance from the centre exceeds this are left out.
  double radius = 0;
  // θ = 0 along this direction, projected into the plane of the centre's
  // face; without it, along that face's first edge (corner 0 to corner 1).
  std::optional<mesh::Vec3> reference_direction;
  // How r is computed.
  DistanceOptions distance;
};

// One vertex of an exponential map: polar (r, theta), theta in (-pi, pi],
// counter-clockwise about the centre face's normal, and
// (u, v) = r (cos, sin) theta.
struct ExpMapVertex {
  int32_t vertex = -1;
  double r = 0;
  double theta = 0;
  double u = 0;
  double v = 0;
};

// The map round centres[i] (read by queries.Read) of every input vertex
// within options.radius, ascending by vertex id (a vertex the repair split:
// its copy of smallest r; midpoints of split long edges are no input
// vertices and are left out). θ runs counter-clockwise about the normal of
// the centre's input face, θ = 0 by default along that face's first input
// edge. `scratch` (optional) keeps the exact solver between calls. Errors:
// InvalidArgument for a radius that is not finite and > 0, and for a
// reference direction that is not finite or is perpendicular to the
// centre's face; those of the engine's distances.
absl::StatusOr<std::vector<ExpMapVertex>> ExpMap(const InputQueries& queries,
                                                 const EnginePoints& centres, size_t i,
                                                 ExpMapOptions options,
                                                 QueryScratch* scratch = nullptr);

}  // namespace geodex::query
