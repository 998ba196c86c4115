#pragma once

// The exact solvers' working memory, kept per thread in a QueryScratch
// (core/query/engine/query_scratch.h) and lent to LocalExact
// (local_exact.h). A header of its own so that the scratch can hold it
// without including the solvers that use it.

#include <memory>
#include <vector>

#include "core/geodesic/confined_geodesic.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/mesh.h"

namespace geodex::query {

// One exact solver over a mesh, and the confined propagations that borrow
// it.
struct ExactSolvers {
  const mesh::Mesh* mesh = nullptr;  // the mesh `exact` was made for
  std::unique_ptr<geodesic::ExactGeodesicSolver> exact;
  // Over exact's mesh, propagating with `exact`; declared after it, so
  // destroyed before it.
  std::unique_ptr<geodesic::ConfinedGeodesicSolver> confined;
};

// The working memory of LocalExact in a caller's QueryScratch: solvers over
// the index's mesh (fields name its vertices) and over the surface before
// its long-edge split (a pair's distance, on fewer faces).
struct ExactScratch {
  ExactSolvers index_mesh;
  ExactSolvers coarse;
  std::vector<int32_t> coarse_seeds;  // a confined call's seeds on the coarse surface
  // The confined solver of the last ConfinedDistance call, for its stats.
  const geodesic::ConfinedGeodesicSolver* last_confined = nullptr;
};

}  // namespace geodex::query
