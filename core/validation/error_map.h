#pragma once

// Where an index errs, for error-driven sample placement (paper §6.5: highly
// curved regions want a finer triangulation; here the index's own measured
// error says where, whatever the cause).
//
// VertexErrorMap propagates exactly from held-out area-uniform surface
// points (a seed of their own, never samples) and asks the index the O(1)
// distance from each to every vertex at least kRefineScale L away (closer
// pairs are refined by default, not answered in O(1)). A pair's error is
// the sum of what both lifts get wrong; averaged over many sources, what
// varies from vertex to vertex is the vertex's own share. The mean squared
// relative error is then averaged over each geodesic triangle, the unit in
// which the index approximates.
//
// SpacingWeights turns such a map into farthest-point spacing weights
// (sampling::FarthestPointSampling): to minimise the total squared error
// for a fixed m when a region's squared error falls as density^-beta, the
// density should grow as error^(1 / (1 + beta)) (Lagrange); farthest-point
// sampling with weight w gives density ~ w^2, so w = error^(1 / (2 (1 +
// beta))). The unfolding's error is second order in the triangle's size
// (curvature x L^2), so its square falls as L^-4 ~ density^-2: beta = 2.
//
// Thread safety: reentrant.

#include <cstdint>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"

namespace geodex::validation {

struct ErrorMapOptions {
  int32_t num_sources = 64;
  // Other than the calibration's and the accuracy harness's.
  uint64_t seed = 0xbb67ae8584caa73bULL;
  int threads = 1;  // 0: all hardware threads
};

// Per vertex of `mesh` (the mesh `index` was built from): the mean squared
// relative error of the O(1) distances from the held-out sources, averaged
// over the vertex's geodesic triangle (area-weighted); 0 for unreferenced
// vertices. Deterministic for a seed, whatever the thread count.
// Errors: FailedPrecondition when the index was not built from this mesh;
// errors of the exact engine; Internal when no pair was measured.
absl::StatusOr<std::vector<double>> VertexErrorMap(const mesh::Mesh& mesh,
                                                   std::shared_ptr<const index::Index> index,
                                                   const ErrorMapOptions& options = {});

// The exponent of SpacingWeights: 1 / (2 (1 + beta)), beta = 2 (header).
inline constexpr double kSpacingExponent = 1.0 / 6.0;

// Spacing weights (error / area-weighted mean error)^exponent per vertex of
// `mesh`; vertices of error 0 take the smallest positive weight, so every
// weight is positive and finite. Errors: InvalidArgument when the map's size
// is not the vertex count or it has a negative or non-finite entry.
absl::StatusOr<std::vector<double>> SpacingWeights(const mesh::Mesh& mesh,
                                                   const std::vector<double>& error_map,
                                                   double exponent = kSpacingExponent);

}  // namespace geodex::validation
