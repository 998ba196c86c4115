#pragma once

// What a query made of the engine's own answers reads: the surface, the
// index's L and two distance functions. QueryEngine::WithDistances hands one
// to such a query, so that the query is a part that depends on this and not
// on the engine, and a new one adds no method to the engine.
//
// Thread safety: a view for the duration of one call; the functions are
// called on the calling thread only.

#include "absl/functional/function_ref.h"
#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

struct SurfaceDistances {
  MeshView view;
  // L of the index (QueryEngine::scale_length): below kRefineScale * L the
  // engine's default answer is refined.
  double scale_length;
  // The engine's distance from `from` to `p`, refined as the caller's
  // DistanceOptions say (QueryEngine::Distance).
  absl::FunctionRef<absl::StatusOr<double>(const mesh::SurfacePoint& from,
                                           const mesh::SurfacePoint& p)>
      distance;
  // The exact distances from `from` to the vertices within `radius`
  // (QueryEngine::FieldWithin): an owned copy, so that `distance` may reuse
  // the solver that made it.
  absl::FunctionRef<absl::StatusOr<RadiusField>(const mesh::SurfacePoint& from, double radius)>
      exact_within;
};

}  // namespace geodex::query
