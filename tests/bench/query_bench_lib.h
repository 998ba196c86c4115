#pragma once

// The pieces of query_bench (query_bench.cc): its flags, the pairs it draws,
// the measurements, and the rows of its tables; and the registry of the
// tables that a query's own bench file adds (QueryBenchTable).
//
// Rates are single-thread and per CPU-second of the measuring thread
// (ThreadCpuSeconds). Not thread-safe.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "tests/bench/near_profile.h"

namespace geodex::bench {

struct QueryBenchOptions {
  std::vector<std::string> indexes;  // empty: a generated sphere
  int pairs = 1'000'000;             // pairs per measurement
  bool field_only = false;           // only the distance field table
  // --<flag>-only of each registered QueryBenchTable: only those tables.
  std::map<std::string, bool> table_only = {};
  int accuracy_pairs = 1000;         // per row of the table against the exact engine
  bool near_profile = false;         // only the near pairs' rates and profile
  // > 0: only the every-distance table, the threshold raised to this many
  // L1000 (DistanceOptions::refine_below_l1000).
  double every_distance = 0;
};

// The command line of query_bench, writing into `options` when parsed.
std::unique_ptr<CLI::App> QueryBenchFlags(QueryBenchOptions* options);

// `n` area-uniform interior points (fixed `seed`): a random face, random
// barycentric weights.
std::vector<mesh::SurfacePoint> InteriorPoints(const index::Index& ix, int n, uint64_t seed);
std::vector<mesh::SurfacePoint> InteriorPoints(int32_t num_faces, int n, uint64_t seed);

// `n` interior points drawn uniformly by area (fixed `seed`): a face with
// probability proportional to its area, uniform barycentric weights.
std::vector<mesh::SurfacePoint> AreaUniformPoints(const index::Index& ix, int n, uint64_t seed);

// `n` points at a random corner of a random face (fixed `seed`).
std::vector<mesh::SurfacePoint> VertexPoints(const index::Index& ix, int n, uint64_t seed);

// The sample matrix packed as its strict lower triangle, m(m-1)/2 float32:
// the storage alternative to the index's full m x m matrix, measured by the
// same gather loop. operator()(a, b) is the index's SampleDistance(a, b).
class PackedMatrix {
 public:
  explicit PackedMatrix(const index::Index& ix);
  double operator()(int32_t a, int32_t b) const;

 private:
  std::vector<float> values_;
};

// The first table: one index's throughput figures.
struct ThroughputFigures {
  int32_t vertices = 0;
  int32_t samples = 0;            // m
  double vertex_rate = 0;         // O1Distance on vertex pairs, pairs/s
  double interior_rate = 0;       // O1Distance on interior pairs
  double batch_rate = 0;          // DistanceBatch, default mode
  double unfold_batch_rate = 0;   // DistanceBatch, pure O(1) mode
  double near_percent = 0;        // share of the random pairs that are near
  double scalar_batch_rate = 0;   // DistanceBatch without the AVX2 lanes
  double gather_rate = 0;         // the loads of a query alone
  double linear_rate = 0;         // the linear-interpolation baseline
  double near_path_us = 0;        // one near pair, path mode
  double near_exact_us = 0;       // one near pair, exact mode
  size_t near_pairs = 0;          // near pairs those two were measured on
  double path_ms = 0;             // one Path, traced
  double corridor_ms = 0;         // one Path with the exact corridor
  double packed_gather_rate = 0;  // the gather loop over PackedMatrix
};

// Measures the first table's figures on `n` pairs of `ix`.
ThroughputFigures MeasureThroughput(std::shared_ptr<const index::Index> ix, int n);

// The first table's header (two lines) and one row of it (no newline).
std::string ThroughputHeader();
std::string ThroughputRow(const std::string& label, const ThroughputFigures& f);

// One row of the refinement table: batch rates of one set of pairs.
struct RefinementFigures {
  std::string pairs;             // "uniform" or a scale bin ("d<L", ...)
  size_t count = 0;              // pairs measured
  double default_rate = 0;       // default mode
  double pure_rate = 0;          // pure O(1) mode
  double pure_uniform_rate = 0;  // pure O(1) on the uniform pairs
  double bounds_rate = 0;        // default with error bounds
  double tolerance_rate = 0;     // tolerance 0.005, at most 300 pairs, once
  double traced_rate = 0;        // default, traces only (no walk)
};

// Measures and prints the refinement table's rows of `ix` on `n` pairs
// (uniform, then each scale bin); a note row when `ix` has no accuracy
// calibration.
void BenchRefinement(const std::string& label, std::shared_ptr<const index::Index> ix, int n);

// The refinement table's title and header, and one row of it (no newline).
std::string RefinementHeader();
std::string RefinementRow(const std::string& label, const RefinementFigures& f);

// A table of one query's timings, registered by the query's own file (one of
// the OBJECT library geodex_query_bench_tables in tests/CMakeLists.txt), so
// that adding a query leaves this library alone.
// query_bench prints every registered table, by flag, after the refinement
// tables and before the distance field table, and gives each a
// --<flag>-only option.
struct QueryBenchTable {
  std::string flag;   // "--<flag>-only" prints only the tables so chosen
  std::string help;   // of that option
  std::string title;  // the line above the header, with --index
  std::function<std::string()> header;
  // Measures and prints the rows of `ix`, labelled `label`.
  std::function<void(const std::string& label, std::shared_ptr<const index::Index> ix)> run;
};

// Adds `table`; for a namespace-scope initializer in the table's file
// (`const bool kRegistered = RegisterQueryBenchTable({...});`), whose
// object file the target must link in whole (an OBJECT library). Returns
// true.
bool RegisterQueryBenchTable(QueryBenchTable table);

// The registered tables, by flag.
std::vector<const QueryBenchTable*> QueryBenchTables();

// One row of the distance field table: one radius.
struct FieldFigures {
  std::string field;     // "3 L", "10 L", "whole mesh, O(1)", "whole mesh, exact"
  double per_field = 0;  // vertices in the field, mean over the sources
  double us = 0;         // one field, microseconds
};

// Measures and prints the distance field rows of `ix`: fields of one source
// at a time (5 interior points) within 3 L and 10 L (exact, FieldWithin),
// against the whole-mesh field (O(1) per vertex, Field) and the exact one
// (FieldWithin with an unbounded radius). Errors: those of the queries.
absl::Status BenchField(const std::string& label, std::shared_ptr<const index::Index> ix);

// The distance field table's header, and one row of it (no newline).
std::string FieldHeader();
std::string FieldRow(const std::string& label, const FieldFigures& f);

// The near pairs of `ix` (the d<L and L-3L bins of the refinement table, at
// most n / 4 each): their batch rates in the default and pure O(1) modes,
// then the L-3L pairs one Distance call at a time, each timed and sorted by
// how the default mode answered it (NearPairStats): rows, then a total row.
// Needs the accuracy calibration (a note row without).
void BenchNearProfile(const std::string& label, std::shared_ptr<const index::Index> ix, int n);

// Area-uniform interior pairs of `ix` (n, as BenchEveryDistance draws them)
// one Distance call each with the threshold raised to `below` L1000, sorted
// as BenchNearProfile sorts them: where the every-distance mode's time goes.
void BenchEveryDistanceProfile(const std::string& label, std::shared_ptr<const index::Index> ix,
                               double below, int n);

// Runs the whole benchmark as the command line asks and returns the exit
// code: 1 when an index cannot be opened.
int RunQueryBench(const QueryBenchOptions& options);

}  // namespace geodex::bench
