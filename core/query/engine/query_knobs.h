#pragma once

// Switches of the query engine for tests and benchmarks: they change how an
// answer is computed, to measure one way against another, never what a
// caller is promised. Production code makes engines with QueryEngine::Create
// and gets the defaults.

#include <memory>

#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

class QueryEngine;

struct QueryKnobs {
  // Straighten traced paths through the faces they cross (funnel algorithm,
  // see path_straightening.h). Off: the raw gradient trace of §6.2.
  bool straighten_paths = true;
  // The pairs the near-pair mode kPath refines first try the corridors of
  // the chord (chord_walk.h), then the gradient trace; off: the trace only.
  // Both are surface paths.
  bool walk_near_pairs = true;
  // DistanceBatch computes far pairs four at a time with AVX2 when the CPU
  // has it (kernel::FarDistances); off: one at a time. The answers are the
  // same to the bit either way.
  bool vector_lanes = true;
};

// QueryEngine::Create with `knobs`.
absl::StatusOr<std::shared_ptr<const QueryEngine>> CreateQueryEngine(
    std::shared_ptr<const index::Index> index, QueryOptions options, QueryKnobs knobs);

}  // namespace geodex::query
