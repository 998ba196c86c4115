#pragma once

// The exact solvers' working memory, kept per thread in a QueryScratch
// (core/query/engine/query_scratch.h) and lent to LocalExact
// (local_exact.h). A header of its own so that the scratch can hold it
// without including the solvers that use it.

#include <memory>

#include "core/geodesic/confined_geodesic.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/mesh.h"

namespace geodex::query {

// The working memory of LocalExact in a caller's QueryScratch: one exact
// solver over the index's mesh, which the confined propagations borrow.
struct ExactScratch {
  const mesh::Mesh* mesh = nullptr;  // the mesh `exact` was made for
  std::unique_ptr<geodesic::ExactGeodesicSolver> exact;
  // Over exact's mesh, propagating with `exact`; declared after it, so
  // destroyed before it.
  std::unique_ptr<geodesic::ConfinedGeodesicSolver> confined;
};

}  // namespace geodex::query
