#include "tests/bench/level_measure.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_format.h"

namespace geodex::bench {
namespace {

std::string P99Cell(const std::vector<double>& vertex, const std::vector<double>& interior,
                    int min_count) {
  auto one = [&](const std::vector<double>& e) -> std::string {
    if (static_cast<int>(e.size()) < min_count) return "-";
    return absl::StrFormat("%.2f", 100 * accuracy::ErrorStats::Of(e).p99);
  };
  return one(vertex) + " / " + one(interior);
}

// Bin of x among doubling edges starting at `first` (bin 0 below it).
int DoublingBin(double x, double first, int bins) {
  if (!(x >= first)) return 0;
  const int b = 1 + static_cast<int>(std::floor(std::log2(x / first)));
  return std::min(b, bins - 1);
}

std::string DoublingName(int bin, double first, int bins) {
  if (bin == 0) return absl::StrFormat("[0,%g)", first);
  const double lo = first * std::pow(2.0, bin - 1);
  if (bin == bins - 1) return absl::StrFormat(">=%g", lo);
  return absl::StrFormat("[%g,%g)", lo, 2 * lo);
}

}  // namespace

int RatioBin(double ratio) { return DoublingBin(ratio, 1, kNumRatioBins); }
std::string RatioBinName(int bin) { return DoublingName(bin, 1, kNumRatioBins); }
int FixedBin(double d) { return DoublingBin(d, 0.5, kNumFixedBins); }
std::string FixedBinName(int bin) { return DoublingName(bin, 0.5, kNumFixedBins); }

LevelErrors BinErrors(const std::vector<validation::ExactPair>& pairs,
                      const std::vector<double>& answers, double l, double l1000) {
  LevelErrors out;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const validation::ExactPair& p = pairs[i];
    if (!(p.exact > 0) || !std::isfinite(answers[i])) continue;
    const double e = (answers[i] - p.exact) / p.exact;
    const int kind = p.vertices ? 0 : 1;
    out.by_ratio[kind][RatioBin(p.exact / l)].push_back(e);
    out.by_fixed[kind][FixedBin(p.exact / l1000)].push_back(e);
  }
  return out;
}

std::vector<double> MeanNeighbours(const index::Index& index, double l,
                                   const std::vector<double>& radii) {
  const int32_t m = index.num_samples();
  std::vector<double> out(radii.size(), 0);
  for (int32_t i = 0; i < m; ++i) {
    for (int32_t j = 0; j < m; ++j) {
      if (j == i) continue;
      const double d = index.SampleDistance(i, j);
      for (size_t k = 0; k < radii.size(); ++k) out[k] += d <= radii[k] * l;
    }
  }
  for (double& x : out) x /= m;
  return out;
}

std::string RatioRow(const std::string& label, const LevelErrors& e, int min_count) {
  std::string row = "| " + label;
  for (int b = 0; b < kNumRatioBins; ++b) {
    row += " | " + P99Cell(e.by_ratio[0][b], e.by_ratio[1][b], min_count);
  }
  return row + " |";
}

std::string FixedRow(const std::string& label, const LevelErrors& e, int min_count) {
  std::string row = "| " + label;
  for (int b = 0; b < kNumFixedBins; ++b) {
    row += " | " + P99Cell(e.by_fixed[0][b], e.by_fixed[1][b], min_count);
  }
  return row + " |";
}

}  // namespace geodex::bench
