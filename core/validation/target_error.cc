#include "core/validation/target_error.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_format.h"
#include "core/query/engine/query_types.h"

namespace geodex::validation {
namespace {

constexpr double kRmsRate = 0.7;
constexpr double kFarRate = 0.8;

}  // namespace

std::string TargetCheckName(int check) {
  if (check == 0) return "uniform RMS";
  return check == 1 ? "vertex >=8 L1000 p99" : "interior >=8 L1000 p99";
}

double TargetLimit(int check, double target) { return check == 0 ? target : 4 * target; }

TargetFigures FiguresOf(const Calibration& calibration, int32_t samples) {
  TargetFigures f;
  f.samples = samples;
  f.measured[0] = calibration.record.uniform_rms;
  f.upper[0] = calibration.confidence.rms_upper;
  f.pairs[0] = 1;  // a calibration always has uniform pairs
  const FixedBands& bands = calibration.bands;
  for (int k = 0; k < 2; ++k) {
    f.measured[1 + k] = bands.far_p99[k];
    f.upper[1 + k] = bands.far_p99_upper[k];
    f.pairs[1 + k] = bands.far_pairs[k];
    for (int b = 0; b < kNumFixedBins; ++b) {
      f.band_p99[k][b] = bands.p99[k][b];
      f.band_pairs[k][b] = bands.pairs[k][b];
    }
  }
  f.unit = bands.unit;
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

double Distance(const TargetFigures& f, double target) {
  const int worst = WorstCheck(f, target);
  return f.upper[worst] / TargetLimit(worst, target);
}

bool TargetSettled(const TargetFigures& f, double target) {
  bool clear_of_every_limit = true;
  for (int c = 0; c < kNumTargetChecks; ++c) {
    if (f.pairs[c] == 0) continue;
    const double limit = TargetLimit(c, target);
    // The lower limit mirrors the upper one about the measured figure.
    if (2 * f.measured[c] - f.upper[c] > limit) return true;
    if (!(f.upper[c] <= kSettledShare * limit)) clear_of_every_limit = false;
  }
  return clear_of_every_limit;
}

std::string BandsLine(const TargetFigures& f) {
  std::string out = "p99 by L1000 band, vertex / interior:";
  for (int b = 0; b < kNumFixedBins; ++b) {
    auto figure = [&](int k) {
      return f.band_pairs[k][b] > 0 ? absl::StrFormat("%.2f%%", 100 * f.band_p99[k][b])
                                    : std::string("-");
    };
    out += absl::StrFormat(" %s %s / %s;", FixedBinName(b), figure(0), figure(1));
  }
  out.pop_back();
  return out;
}

std::string BandsText(const TargetFigures& f, double scale_length) {
  std::string out = absl::StrFormat("band_unit = %.6g\nband_refined_below = %.6g\n", f.unit,
                                    f.unit > 0 ? query::kRefineScale * scale_length / f.unit : 0);
  static const char* const kKind[2] = {"vertex", "interior"};
  static const char* const kKey[kNumFixedBins] = {"0_0.5", "0.5_1", "1_2",   "2_4",
                                                  "4_8",   "8_16",  "16_inf"};
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < kNumFixedBins; ++b) {
      out += absl::StrFormat("band_p99_%s_%s = %.6g\nband_pairs_%s_%s = %d\n", kKind[k], kKey[b],
                             f.band_p99[k][b], kKind[k], kKey[b], f.band_pairs[k][b]);
    }
  }
  // The judged checks, so that the report's verdict and its figures are
  // one measurement (core/index/index_report.h reads them).
  static const char* const kCheckKey[kNumTargetChecks] = {"uniform_rms", "vertex_far_p99",
                                                          "interior_far_p99"};
  for (int c = 0; c < kNumTargetChecks; ++c) {
    out += absl::StrFormat("check_%s = %.6g %.6g %d\n", kCheckKey[c], f.measured[c], f.upper[c],
                           f.pairs[c]);
  }
  return out;
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
    const double rate = c == 0 ? kRmsRate : kFarRate;
    want = std::max(want, last.samples * std::pow(last.upper[c] / (options.aim * limit), 1 / rate));
  }
  want = std::min(want, last.samples * options.max_growth);
  return static_cast<int32_t>(std::min<double>(cap, std::ceil(want)));
}

int32_t SamplesWithinBytes(int64_t budget, int32_t samples, int64_t bytes) {
  // The coded matrix: m (m - 1) / 2 codes of 3 bytes (sample_matrix.h).
  auto matrix = [](double m) { return 1.5 * m * (m - 1); };
  const double per_sample = std::max(0.0, bytes - matrix(samples)) / std::max(samples, 1);
  // The positive root of 1.5 m^2 + (per_sample - 1.5) m - budget = 0.
  const double a = 1.5, b = per_sample - 1.5;
  const double m = (-b + std::sqrt(b * b + 4 * a * static_cast<double>(budget))) / (2 * a);
  return static_cast<int32_t>(std::clamp(std::floor(m), 3.0, 2e9));
}

}  // namespace geodex::validation
