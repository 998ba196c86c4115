// pairs_rate: the in-process rate of given pairs, the counterpart of
// `geodex bench --save-pairs FILE` through the service. The pairs (in the
// ids of the mesh file, as the service takes them) are answered as the
// service answers a batch: read through the facade (InputQueries::Read),
// then DistanceBatch with one scratch, in batches of --batch pairs, on one
// thread. After one pass to warm up (the lazy exact mesh, the solver's
// buffers), as `geodex bench --warmup` does, prints pairs per CPU-second of
// that thread over --passes more passes (a sustained rate, as the bench's,
// not the best pass), and a digest of the answers' bits.
//
//   pairs_rate --index X.gdx --pairs FILE [--batch 256] [--passes 3]
//              [--refine-below X] [--near-pairs path|unfold|exact]

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "core/mesh/pairs_io.h"
#include "core/query/input_queries.h"
#include "tests/bench/bench_timing.h"

namespace geodex::bench {
namespace {

struct Options {
  std::string index, pairs;
  int batch = 256;
  int passes = 3;
  double refine_below = 0;
  std::string near_pairs = "path";
};

int Run(const Options& o) {
  auto queries = query::InputQueries::Open(o.index);
  if (!queries.ok()) {
    std::fprintf(stderr, "%s\n", queries.status().ToString().c_str());
    return 1;
  }
  auto text = mesh::ReadFileOrStdin(o.pairs);
  if (!text.ok()) {
    std::fprintf(stderr, "%s\n", text.status().ToString().c_str());
    return 1;
  }
  auto pairs = mesh::ParsePairs(*text);
  if (!pairs.ok() || pairs->empty()) {
    std::fprintf(stderr, "%s: %s\n", o.pairs.c_str(),
                 pairs.ok() ? "no pairs" : pairs.status().ToString().c_str());
    return 1;
  }
  query::DistanceOptions options;
  options.refine_below_l1000 = o.refine_below;
  options.near_pairs = o.near_pairs == "unfold"  ? query::NearPairs::kUnfold
                       : o.near_pairs == "exact" ? query::NearPairs::kExact
                                                 : query::NearPairs::kPath;
  const size_t n = pairs->size();
  std::vector<mesh::SurfacePoint> a(n), b(n);
  for (size_t i = 0; i < n; ++i) a[i] = (*pairs)[i].a, b[i] = (*pairs)[i].b;
  std::vector<double> out(n);
  query::QueryScratch scratch;
  double seconds = 0;
  for (int pass = 0; pass <= o.passes; ++pass) {
    const double start = ThreadCpuSeconds();
    for (size_t from = 0; from < n; from += static_cast<size_t>(o.batch)) {
      const size_t count = std::min(n - from, static_cast<size_t>(o.batch));
      query::EnginePoints read_a, read_b;
      absl::Status s = (*queries)->Read(std::span(a).subspan(from, count), query::Named("a"), &read_a);
      if (s.ok()) s = (*queries)->Read(std::span(b).subspan(from, count), query::Named("b"), &read_b);
      if (s.ok()) {
        s = (*queries)->DistanceBatch(read_a, read_b, std::span(out).subspan(from, count), options,
                                      &scratch);
      }
      if (!s.ok()) {
        std::fprintf(stderr, "pairs %zu-%zu: %s\n", from, from + count, s.ToString().c_str());
        return 1;
      }
    }
    if (pass > 0) seconds += ThreadCpuSeconds() - start;  // pass 0 warms up
  }
  const double rate = static_cast<double>(n) * o.passes / seconds;
  uint64_t digest = 14695981039346656037ull;  // FNV-1a over the answers' bits
  for (double d : out) digest = (digest ^ std::bit_cast<uint64_t>(d)) * 1099511628211ull;
  std::printf("| %s | %zu | %.1fK | %016llx |\n", o.index.c_str(), n, rate / 1e3,
              static_cast<unsigned long long>(digest));
  return 0;
}

}  // namespace
}  // namespace geodex::bench

int main(int argc, char** argv) {
  CLI::App app("pairs_rate: given pairs answered in process as the service answers a batch, one thread");
  geodex::bench::Options o;
  app.add_option("--index", o.index, "The index")->required()->check(CLI::ExistingFile);
  app.add_option("--pairs", o.pairs, "Pairs 'fa a0 a1 a2 fb b0 b1 b2' (geodex bench --save-pairs)")
      ->required();
  app.add_option("--batch", o.batch, "Pairs a batch")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--passes", o.passes, "Passes over the pairs after one to warm up; their rate is printed")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--refine-below", o.refine_below, "DistanceOptions::refine_below_l1000 (0: the index's)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--near-pairs", o.near_pairs, "Near-pair mode")
      ->check(CLI::IsMember({"path", "unfold", "exact"}))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  return geodex::bench::Run(o);
}
