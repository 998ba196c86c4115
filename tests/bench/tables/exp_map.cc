// query_bench's exponential map table (core/query/exp_map.h),
// registered with the bench's tables (QueryBenchTable, query_bench_lib.h):
// the time of one map round an interior point for radii of 3 L, 10 L and the
// whole mesh, in the default mode and with r from the pure O(1) distance.

#include <cstdio>
#include <limits>
#include <memory>
#include <string>

#include "absl/strings/str_format.h"
#include "core/query/exp_map.h"
#include "core/query/input_queries.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/bench_timing.h"
#include "tests/bench/query_bench_lib.h"

namespace geodex::bench {
namespace {

std::string ExpMapHeader() {
  return MarkdownHeader({"index", "radius", "vertices mapped", "one map, default",
                         "one map, pure O(1)", "per vertex, default"});
}

// Five interior centres, each mapped once per radius and mode after a
// warm-up map (the lazy exact mesh); times per map.
void BenchExpMap(const std::string& label, std::shared_ptr<const index::Index> ix) {
  auto queries = *query::InputQueries::Create(ix);
  // Interior points of the input's faces, which the facade reads.
  const auto points = InteriorPoints(queries->num_faces(), 5, 7);
  query::EnginePoints centres;
  if (const absl::Status read = queries->Read(points, query::Named("centre"), &centres);
      !read.ok()) {
    std::printf("%s: %s\n", label.c_str(), read.ToString().c_str());
    return;
  }
  const double l = queries->scale_length();
  for (const double radius : {3 * l, 10 * l, std::numeric_limits<double>::max()}) {
    double ms[2];
    size_t mapped = 0;
    for (int mode = 0; mode < 2; ++mode) {
      query::ExpMapOptions options;
      options.radius = radius;
      if (mode == 1) options.distance.near_pairs = query::NearPairs::kUnfold;
      query::QueryScratch scratch;
      auto map = [&](size_t i) { return query::ExpMap(*queries, centres, i, options, &scratch); };
      (void)map(0);  // the lazy exact mesh
      mapped = 0;
      const double t0 = ThreadCpuSeconds();
      for (size_t i = 0; i < centres.size(); ++i) mapped += map(i)->size();
      ms[mode] = 1e3 * (ThreadCpuSeconds() - t0) / centres.size();
    }
    const double per_map = static_cast<double>(mapped) / centres.size();
    const std::string name = radius == std::numeric_limits<double>::max()
                                 ? "whole mesh"
                                 : absl::StrFormat("%.0f L", radius / l);
    const std::string row = MarkdownRow(
        {label, name, absl::StrFormat("%.0f", per_map), absl::StrFormat("%.2f ms", ms[0]),
         absl::StrFormat("%.2f ms", ms[1]), absl::StrFormat("%.2f us", 1e3 * ms[0] / per_map)});
    std::printf("%s\n", row.c_str());
  }
}

[[maybe_unused]] const bool kRegistered = RegisterQueryBenchTable({
    .flag = "expmap",
    .help = "Only the exponential map table",
    .title = "Exponential map (5 interior centres)",
    .header = ExpMapHeader,
    .run = BenchExpMap,
});

}  // namespace
}  // namespace geodex::bench
