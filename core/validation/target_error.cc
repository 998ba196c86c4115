#include "core/validation/target_error.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_format.h"

namespace geodex::validation {
namespace {

constexpr double kRmsRate = 0.7;
constexpr double kBinRate = 0.6;

int KindOf(int check) { return (check - 1) / kNumScaleBins; }
int BinOf(int check) { return (check - 1) % kNumScaleBins; }

}  // namespace

std::string TargetCheckName(int check) {
  if (check == 0) return "uniform RMS";
  return absl::StrFormat("%s %s p99",
                         KindOf(check) == BinConfidence::kVertex ? "vertex" : "interior",
                         ScaleBinName(BinOf(check)));
}

double TargetLimit(int check, double target) {
  if (check == 0) return target;
  return BinOf(check) < 2 ? 2 * target : 4 * target;
}

TargetFigures FiguresOf(const Calibration& calibration, int32_t samples) {
  TargetFigures f;
  f.samples = samples;
  f.measured[0] = calibration.record.uniform_rms;
  f.upper[0] = calibration.confidence.rms_upper;
  f.pairs[0] = 1;  // a calibration always has uniform pairs
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < kNumScaleBins; ++b) {
      const int check = 1 + k * kNumScaleBins + b;
      f.measured[check] = calibration.bins.p99[k][b];
      f.upper[check] = calibration.bins.p99_upper[k][b];
      f.pairs[check] = calibration.bins.pairs[k][b];
    }
  }
  return f;
}

bool TargetMet(const TargetFigures& f, double target) {
  for (int c = 0; c < kNumTargetChecks; ++c) {
    if (f.pairs[c] > 0 && !(f.upper[c] <= TargetLimit(c, target))) return false;
  }
  return true;
}

int WorstCheck(const TargetFigures& f, double target) {
  int worst = 0;
  double worst_ratio = -1;
  for (int c = 0; c < kNumTargetChecks; ++c) {
    if (f.pairs[c] == 0) continue;
    const double ratio = f.upper[c] / TargetLimit(c, target);
    if (ratio > worst_ratio) worst = c, worst_ratio = ratio;
  }
  return worst;
}

std::string FiguresText(const TargetFigures& f, double target) {
  std::string out = absl::StrFormat("m = %d:", f.samples);
  for (int c = 0; c < kNumTargetChecks; ++c) {
    if (f.pairs[c] == 0) {
      out += absl::StrFormat(" %s no pairs;", TargetCheckName(c));
      continue;
    }
    const double limit = TargetLimit(c, target);
    out +=
        absl::StrFormat(" %s %.3f%% (%.3f%%) / %.2f%%%s;", TargetCheckName(c), 100 * f.measured[c],
                        100 * f.upper[c], 100 * limit, f.upper[c] <= limit ? "" : " MISSED");
  }
  out.pop_back();
  return out;
}

int32_t PredictSamples(std::span<const TargetFigures> rounds, double target, int32_t cap,
                       const PredictionOptions& options) {
  const TargetFigures& last = rounds.back();
  double want = last.samples * options.min_growth;
  for (int c = 0; c < kNumTargetChecks; ++c) {
    const double limit = TargetLimit(c, target);
    if (last.pairs[c] == 0 || last.upper[c] <= limit) continue;
    const double rate = c == 0 ? kRmsRate : kBinRate;
    want = std::max(want, last.samples * std::pow(last.upper[c] / (options.aim * limit), 1 / rate));
  }
  want = std::min(want, last.samples * options.max_growth);
  return static_cast<int32_t>(std::min<double>(cap, std::ceil(want)));
}

int32_t SamplesWithinBytes(int64_t budget, int32_t samples, int64_t bytes) {
  // The packed matrix: m (m - 1) / 2 floats.
  auto matrix = [](double m) { return 2 * m * (m - 1); };
  const double per_sample = std::max(0.0, bytes - matrix(samples)) / std::max(samples, 1);
  // The positive root of 2 m^2 + (per_sample - 2) m - budget = 0.
  const double b = per_sample - 2;
  const double m = (-b + std::sqrt(b * b + 8.0 * static_cast<double>(budget))) / 4;
  return static_cast<int32_t>(std::clamp(std::floor(m), 3.0, 2e9));
}

}  // namespace geodex::validation
