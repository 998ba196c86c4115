#pragma once

// `geodex bench`: a load generator for a geodex server.

#include <cstdint>
#include <map>
#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {

struct BenchOptions {
  ModelRef model;
  int concurrency = 4;  // workers, each with its own calls in flight
  absl::Duration duration = absl::Seconds(10);
  absl::Duration warmup = absl::Seconds(1);  // calls made then are not counted
  int batch = 256;                           // pairs per call (or per stream batch)
  // "unary": each worker makes one Distance call at a time. "stream": each
  // worker keeps `window` batches in flight on one StreamDistances session.
  std::string mode = "unary";
  int window = 4;
  NearPairs near_pairs = NearPairs::kModelDefault;
  uint64_t seed = 1;
};

struct BenchReport {
  int64_t calls = 0;  // successful calls (unary) or batches (stream)
  int64_t pairs = 0;
  std::map<std::string, int64_t> errors;  // status code name -> count
  absl::Duration elapsed;
  double p50_ms = 0, p90_ms = 0, p99_ms = 0, p999_ms = 0, max_ms = 0, mean_ms = 0;
};

// Runs the load against random valid pairs on `options.model` (GetModel gives
// its face count). Errors: the GetModel error; UNAVAILABLE-like errors of the
// calls themselves are counted in the report, not returned, unless no call
// succeeded (then the first such error).
absl::StatusOr<BenchReport> RunBench(const Client& client, const BenchOptions& options);

// The report as printed by `geodex bench`.
std::string FormatBenchReport(const BenchOptions& options, const BenchReport& report);

}  // namespace geodex::client::cli
