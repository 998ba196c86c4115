#pragma once

// Per-thread working memory of the queries that are not O(1): the exact
// solvers that refinements and exact neighbourhoods run (their arrays grow
// with the mesh, so a thread keeps them and reuses them). Optional wherever a query
// takes it: without one, a query makes its own for the call.
//
// Thread safety: one QueryScratch per thread; it is not shared.
//
//   query::QueryScratch scratch;  // per worker thread
//   GEODEX_RETURN_IF_ERROR(queries->DistanceBatch(a, b, out, options, &scratch));

#include <memory>

namespace geodex::mesh {
class Mesh;
}  // namespace geodex::mesh
namespace geodex::geodesic {
class ExactGeodesicSolver;
class ConfinedGeodesicSolver;
}  // namespace geodex::geodesic

namespace geodex::query {

class LocalExact;

class QueryScratch {
 public:
  QueryScratch();
  ~QueryScratch();
  QueryScratch(QueryScratch&&) noexcept;
  QueryScratch& operator=(QueryScratch&&) noexcept;

 private:
  friend class LocalExact;
  std::unique_ptr<geodesic::ExactGeodesicSolver> solver_;
  const mesh::Mesh* mesh_ = nullptr;                            // the mesh solver_ was made for
  std::unique_ptr<geodesic::ConfinedGeodesicSolver> confined_;  // over confined_->mesh()
};

}  // namespace geodex::query
