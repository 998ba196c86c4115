#include "core/query/query_scratch.h"

#include <memory>

// QueryScratch's special members and accessors, which need the parts it
// holds complete. Apart from query_scratch.h's own unit: the parts'
// headers include query_scratch.h, and a unit of its own including them
// would close an include loop.
#include "core/query/internal/exact/local_exact.h"
#include "core/query/internal/paths/chord_walk.h"

namespace geodex::query {

QueryScratch::QueryScratch() = default;
QueryScratch::~QueryScratch() = default;
QueryScratch::QueryScratch(QueryScratch&&) noexcept = default;
QueryScratch& QueryScratch::operator=(QueryScratch&&) noexcept = default;

QueryScratch::Solvers& QueryScratch::solvers() {
  if (solvers_ == nullptr) solvers_ = std::make_unique<Solvers>();
  return *solvers_;
}

QueryScratch::Walks& QueryScratch::walks() {
  if (walks_ == nullptr) walks_ = std::make_unique<Walks>();
  return *walks_;
}

}  // namespace geodex::query
