#pragma once

// Per-thread working memory of the queries that are not O(1): the exact
// solver that refinements and exact neighbourhoods run (its arrays grow with
// the mesh, so a thread keeps it and reuses it). Optional wherever a query
// takes it: without one, a query makes its own for the call.
//
// Thread safety: one QueryScratch per thread; it is not shared.
//
//   query::QueryScratch scratch;  // per worker thread
//   GEODEX_RETURN_IF_ERROR(queries->DistanceBatch(a, b, out, options, &scratch));

#include <memory>

namespace geodex::query {

class QueryScratch {
 public:
  QueryScratch();
  ~QueryScratch();
  QueryScratch(QueryScratch&&) noexcept;
  QueryScratch& operator=(QueryScratch&&) noexcept;

  // What the scratch holds: one exact solver over one mesh (and the state of
  // propagations confined to parts of it, which run on that solver). Its
  // definition is the query engine's own (internal/exact/local_exact.h);
  // callers only pass the scratch along.
  struct Solvers;
  // The solvers, made (empty) on first use: a scratch that no query needs
  // allocates nothing.
  Solvers& solvers();

 private:
  std::unique_ptr<Solvers> solvers_;
};

}  // namespace geodex::query
