// Query throughput: single-thread queries per second of the constant-time
// engine, next to (a) a gather-only loop that performs just the memory loads a
// query needs (the practical limit) and (b) the paper's linear-interpolation
// baseline (§6.3), all in the same run on the same pairs. Rates are per
// CPU-second of the measuring thread.
//
// The batch runs in the default mode (near and close pairs by path length)
// and in the pure O(1) mode; the share of random pairs that are near is printed with it.
// Vertex and interior pairs/s are single O1Distance calls (O(1)). The
// cost of one near pair in the path and exact modes is measured apart, on
// near pairs drawn on purpose. So is the time of one Path between random
// interior points, traced (O(k)) and with an exact corridor of 8 steps.
//
//   query_bench [--index FILE.gdx]... [--pairs N] [--accuracy-pairs N] [--near-profile]
//
// --near-profile prints only the near pairs' table: the batch rates at d<L
// and L-3L of the O(1) answer, and the L-3L pairs one call at a time by how
// the default mode answered them (walk, releases, exact solve), with their
// cost, the faces their walks crossed and the exact solver's rounds.
//
// Then, per index with its accuracy calibration, the refinement table: the
// default mode, the pure O(1) mode, the default with error bounds and with
// a tolerance of 0.005, on uniform pairs and on pairs at each scale.
//
// Then, per index with its calibration, the refined answers against the
// exact engine (refinement_accuracy.h): per scale bin, vertex and interior
// pairs, rate, error quantiles, bound coverage and the share answered
// exactly; tolerances 0.005 and 0.001 on area-uniform pairs.
//
// Then the tables that queries register from their own files (QueryBenchTable
// in query_bench_lib.h), each with its --<flag>-only option.
//
// Without --index it builds an index of a generated sphere (a note says so).
//
// The measurements and the tables are in query_bench_lib.h.

#include "tests/bench/bench_flags.h"
#include "tests/bench/query_bench_lib.h"

int main(int argc, char** argv) {
  geodex::bench::QueryBenchOptions options;
  const auto app = geodex::bench::QueryBenchFlags(&options);
  if (const auto exit_code = geodex::bench::ParseFlags(*app, argc, argv)) return *exit_code;
  return geodex::bench::RunQueryBench(options);
}
