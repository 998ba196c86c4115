#pragma once

// One Distance call a pair, each timed and sorted by how the refinement
// answered it (shot k, walk, releases, trace, exact, O(1)): query_bench's
// near-pair and every-distance profiles.

#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/query/internal/query_engine.h"

namespace geodex::bench {

// The pairs (x[i], y[i]) one Distance call each under `options`, each
// timed (the least of three calls) and sorted by how the refinement
// answered it: a row a class, then a total row named `total_how`, printed
// as NearProfileRowText rows.
void PrintProfileRows(const std::string& label, const query::QueryEngine& engine,
                      const std::vector<mesh::SurfacePoint>& x,
                      const std::vector<mesh::SurfacePoint>& y,
                      const query::DistanceOptions& options, const std::string& total_how);

}  // namespace geodex::bench
