#pragma once

// The model the request fuzzer queries and whose requests seed its corpus: a
// small generated sphere, indexed with its accuracy calibration (so that
// tolerance and error-bound requests are accepted).

#include <memory>
#include <string>

#include "core/query/input_queries.h"

namespace geodex::fuzz {

// Bytes of the index (built once per process; thread-safe). Aborts on error:
// a fuzz target cannot run without it.
const std::string& FuzzIndexBytes();
// The queries of FuzzIndexBytes() (built once per process; thread-safe).
const query::InputQueries& FuzzQueries();

}  // namespace geodex::fuzz
