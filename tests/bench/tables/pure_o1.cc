// query_bench's pure O(1) table: DistanceBatch with near pairs unfolded too
// (NearPairs::kUnfold), the paper's constant-time answer for every pair, on
// area-uniform interior pairs and on vertex pairs, one thread, per
// CPU-second (the best of five passes). The digest is a hash of the
// answers' bits, so that two builds can be shown to answer the same to the
// bit (same index, same --pairs).

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/query/engine/query_engine.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/bench_timing.h"
#include "tests/bench/query_bench_lib.h"

namespace geodex::bench {
namespace {

constexpr int kPairs = 1'000'000;
constexpr int kPasses = 5;

std::string PureO1Header() {
  return MarkdownHeader({"index", "m", "interior pairs/s", "vertex pairs/s", "answers digest"});
}

// FNV-1a over the answers' bit patterns.
uint64_t Digest(std::span<const double> values, uint64_t h) {
  for (const double v : values) {
    const uint64_t bits = std::bit_cast<uint64_t>(v);
    for (int byte = 0; byte < 8; ++byte) {
      h ^= (bits >> (8 * byte)) & 0xff;
      h *= 1099511628211ull;
    }
  }
  return h;
}

// The best pairs/s of kPasses passes over (a, b); the answers in `out`.
double PureRate(const query::QueryEngine& engine, std::span<const mesh::SurfacePoint> a,
                std::span<const mesh::SurfacePoint> b, std::vector<double>* out) {
  out->assign(a.size(), 0);
  double best = 0;
  for (int pass = 0; pass < kPasses; ++pass) {
    const double start = ThreadCpuSeconds();
    if (!engine.DistanceBatch(a, b, *out, {.near_pairs = query::NearPairs::kUnfold}).ok()) return 0;
    best = std::max(best, a.size() / (ThreadCpuSeconds() - start));
  }
  return best;
}

void BenchPureO1(const std::string& label, std::shared_ptr<const index::Index> ix) {
  auto engine = *query::QueryEngine::Create(ix);
  const auto a = InteriorPoints(*ix, kPairs, 1), b = InteriorPoints(*ix, kPairs, 2);
  const auto va = VertexPoints(*ix, kPairs, 3), vb = VertexPoints(*ix, kPairs, 4);
  std::vector<double> interior, vertex;
  const double interior_rate = PureRate(*engine, a, b, &interior);
  const double vertex_rate = PureRate(*engine, va, vb, &vertex);
  const uint64_t digest = Digest(vertex, Digest(interior, 14695981039346656037ull));
  std::printf("%s\n", MarkdownRow({label, absl::StrFormat("%d", ix->num_samples()),
                                   absl::StrFormat("%.2fM", interior_rate / 1e6),
                                   absl::StrFormat("%.2fM", vertex_rate / 1e6),
                                   absl::StrFormat("%016x", digest)})
                          .c_str());
}

[[maybe_unused]] const bool kRegistered = RegisterQueryBenchTable({
    .flag = "pure-o1",
    .help = "Only the pure O(1) batch table",
    .title = "Pure O(1) batch (1,000,000 pairs, best of 5 passes)",
    .header = PureO1Header,
    .run = BenchPureO1,
});

}  // namespace
}  // namespace geodex::bench
