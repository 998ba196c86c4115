// near_pairs_check: the default answer of near pairs against the exact mode
// of the same index. Near pairs are a random point and one a random walk of
// 1 to 12 faces away whose O(1) distance is below 3L (the index's own L),
// vertex and interior points apart. Prints, per kind: the default batch's
// rate with bounds and the exact mode's (per CPU-second of one thread), the
// |relative error| of the default answer against the exact mode's (p99,
// p99.9, largest, how many beyond 2%), the share within its bound and the
// share answered exactly.
//
//   near_pairs_check --index X.gdx... [--pairs 100000]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "core/index/index.h"
#include "core/query/engine/internal/bounds/error_bounds.h"
#include "core/query/engine/query_engine.h"
#include "tests/bench/bench_timing.h"
#include "tests/bench/refinement_accuracy.h"

namespace geodex {
namespace {

using mesh::SurfacePoint;

double Quantile(std::vector<double> x, double q) {
  if (x.empty()) return NAN;
  std::sort(x.begin(), x.end());
  return x[std::min(x.size() - 1, static_cast<size_t>(q * x.size()))];
}

int Run(const std::string& path, int pairs) {
  absl::StatusOr<std::shared_ptr<const index::Index>> ix = index::Index::Open(path);
  if (!ix.ok()) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), std::string(ix.status().message()).c_str());
    return 1;
  }
  if ((*ix)->accuracy() == nullptr) {
    std::fprintf(stderr, "%s: not calibrated\n", path.c_str());
    return 1;
  }
  auto engine = *query::QueryEngine::Create(*ix);
  const double scale = engine->scale_length();
  query::QueryScratch scratch;
  for (const bool vertex : {true, false}) {
    std::mt19937_64 rng(vertex ? 31 : 32);
    std::vector<SurfacePoint> a, b;
    while (static_cast<int>(a.size()) < pairs) {
      const int32_t f = static_cast<int32_t>(rng() % (*ix)->num_faces());
      int32_t g = f;
      for (int step = 1 + static_cast<int>(rng() % 12); step > 0; --step) {
        const int32_t twin = (*ix)->twins()[3 * g + static_cast<int32_t>(rng() % 3)];
        if (twin >= 0) g = twin / 3;
      }
      const SurfacePoint p = bench::RandomPoint(f, vertex, rng);
      const SurfacePoint q = bench::RandomPoint(g, vertex, rng);
      const double d = engine->O1Distance(p, q);
      if (!(d > 0) || !(d < 3 * scale)) continue;
      a.push_back(p);
      b.push_back(q);
    }
    // The engine's exact mesh and the scratch's solvers are made before the
    // clocks run.
    (void)engine->Distance(a[0], b[0], {.near_pairs = query::NearPairs::kExact}, &scratch);
    std::vector<double> got(a.size()), bound(a.size()), exact(a.size());
    double start = bench::ThreadCpuSeconds();
    if (!engine->DistanceBatch(a, b, got, {}, &scratch, bound).ok()) return 1;
    const double rate = a.size() / (bench::ThreadCpuSeconds() - start);
    start = bench::ThreadCpuSeconds();
    if (!engine->DistanceBatch(a, b, exact, {.near_pairs = query::NearPairs::kExact}, &scratch)
             .ok()) {
      return 1;
    }
    const double exact_rate = a.size() / (bench::ThreadCpuSeconds() - start);
    std::vector<double> errors;
    size_t covered = 0, refined_exactly = 0, beyond = 0;
    double worst_bound = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      if (!(exact[i] > 0)) continue;
      const double e = std::abs(got[i] - exact[i]);
      errors.push_back(e / exact[i]);
      covered += e <= bound[i] + 1e-9 * exact[i];
      refined_exactly += bound[i] <= query::kExactRelativeBound * got[i];
      if (e / exact[i] > 0.02) {
        ++beyond;
        worst_bound = std::max(worst_bound, bound[i] / exact[i]);
      }
    }
    const double n = static_cast<double>(errors.size());
    std::printf(
        "%s %-8s | %zu pairs below 3L | default %.0f/s, exact mode %.0f/s | p99 %.4f%% p99.9 "
        "%.3f%% max %.3f%% | %zu beyond 2%% | within bound %.3f%% | exact %.1f%%\n",
        path.substr(path.find_last_of('/') + 1).c_str(), vertex ? "vertex" : "interior",
        errors.size(), rate, exact_rate, 100 * Quantile(errors, 0.99),
        100 * Quantile(errors, 0.999),
        100 * (errors.empty() ? NAN : *std::max_element(errors.begin(), errors.end())), beyond,
        100 * covered / n, 100 * refined_exactly / n);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app{"Near pairs: the default answer against the exact mode"};
  std::vector<std::string> indexes;
  int pairs = 100000;
  app.add_option("--index", indexes, "index files")->required();
  app.add_option("--pairs", pairs, "near pairs of each kind");
  CLI11_PARSE(app, argc, argv);
  int status = 0;
  for (const std::string& path : indexes) status |= geodex::Run(path, pairs);
  return status;
}
