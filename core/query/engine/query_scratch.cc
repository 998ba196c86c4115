#include "core/query/engine/query_scratch.h"

#include <memory>

#include "core/query/engine/internal/exact/exact_scratch.h"
#include "core/query/engine/internal/paths/walk_scratch.h"

namespace geodex::query {

QueryScratch::QueryScratch() = default;
QueryScratch::~QueryScratch() = default;
QueryScratch::QueryScratch(QueryScratch&&) noexcept = default;
QueryScratch& QueryScratch::operator=(QueryScratch&&) noexcept = default;

ExactScratch& QueryScratch::solvers() {
  if (solvers_ == nullptr) solvers_ = std::make_unique<ExactScratch>();
  return *solvers_;
}

WalkScratch& QueryScratch::walks() {
  if (walks_ == nullptr) walks_ = std::make_unique<WalkScratch>();
  return *walks_;
}

}  // namespace geodex::query
