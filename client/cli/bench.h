#pragma once

// `geodex bench`: a load generator for a geodex server. It measures two
// kinds of pairs: uniform ones (a random face each, weights uniform), most of
// them far apart and answered in O(1), and near ones, 1L to 3L apart (L the
// model's sample spacing), where the server refines its answers (core/
// README.md, "Near pairs") and the rate is what local queries get.

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

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
  // DistanceQuery::refine_below of every call (8: the every-distance mode).
  double refine_below = 0;
  uint64_t seed = 1;
  // Which pairs: kUniform as RandomPairs, kArea as AreaUniformPairs, kNear
  // as DrawNearPairs between near_from and near_to scale lengths.
  enum class Pairs { kUniform, kArea, kNear };
  Pairs pairs = Pairs::kUniform;
  double near_from = 1, near_to = 3;
  // When not empty, the pairs drawn are written to this file first (as
  // FormatPairs writes them, which geodex-query --pairs reads), so that the
  // same pairs can be timed in process (tests/bench/pairs_rate.cc) beside
  // the rate through the service: the pool the calls take their batches
  // from, in order.
  std::string save_pairs;
};

struct BenchReport {
  double scale_length = 0;  // L of the model (near pairs only)
  int64_t calls = 0;        // successful calls (unary) or batches (stream)
  int64_t pairs = 0;
  std::map<std::string, int64_t> errors;  // status code name -> count
  absl::Duration elapsed;
  double p50_ms = 0, p90_ms = 0, p99_ms = 0, p999_ms = 0, max_ms = 0, mean_ms = 0;
};

// `count` uniform pairs: a random face of `num_faces` each, weights uniform
// on the triangle.
std::vector<PointPair> RandomPairs(int64_t num_faces, size_t count, uint64_t seed);

// `count` area-uniform pairs of `mesh`: each point's face drawn with
// probability proportional to its area, weights uniform on the triangle.
// The pairs the in-process benchmarks and the accuracy harness draw, so
// that the rates through the service compare with theirs. Empty for a mesh
// without area. Deterministic for a seed.
std::vector<PointPair> AreaUniformPairs(const Mesh& mesh, size_t count, uint64_t seed);

// L = sqrt(2 A / (sqrt(3) m)) of `mesh` (area A) tiled by `num_samples` (m)
// samples: the edge of an equilateral geodesic triangle, as the server's
// engine defines it. 0 for a mesh without area or samples.
double ScaleLength(const Mesh& mesh, int64_t num_samples);

// Up to `count` near pairs of `mesh`: p a uniform point of a random face, q a
// uniform point of a random face among those reached from p's face across
// edges without leaving the ball of radius `hi` round p (the same sheet of
// the surface, not one that merely passes close), with hi >= |p - q| >= lo.
// Straight-line distances, so the geodesic one is at least lo and, on a
// surface that is flat at this scale, close to |p - q|. Points whose ball
// holds no such q are skipped: fewer pairs only when few or none exist
// (a mesh smaller than lo). Deterministic for a seed.
std::vector<PointPair> DrawNearPairs(const Mesh& mesh, double lo, double hi, size_t count,
                                     uint64_t seed);

// Runs the load against valid pairs on `options.model` of the kind
// options.pairs says (GetModel gives its face count and m; near pairs also
// read its mesh, GetMesh, for L and the draw). Errors: the GetModel or
// GetMesh error; FailedPrecondition when no near pair can be drawn;
// UNAVAILABLE-like errors of the calls themselves are counted in the report,
// not returned, unless no call succeeded (then the first such error).
absl::StatusOr<BenchReport> RunBench(const Client& client, const BenchOptions& options);

// The report as printed by `geodex bench`, for the pairs options.pairs says.
std::string FormatBenchReport(const BenchOptions& options, const BenchReport& report);

}  // namespace geodex::client::cli
