#include "core/query/query_scratch.h"

#include <memory>

// The definitions of the parts a scratch holds: its special members need
// them complete.
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
