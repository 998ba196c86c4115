#include "core/validation/calibration.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/common/threads.h"
#include "core/index/coarse_surface.h"
#include "core/query/engine/input_ids.h"
#include "core/query/engine/query_engine.h"

namespace geodex::validation {
namespace {

int AccuracyBinOf(double d, double scale_length) {
  const double x = d / scale_length;
  int b = 0;
  while (b + 1 < index::kAccuracyBins && x >= index::kAccuracyBinUpper[b]) ++b;
  return b;
}

double Quantile(std::vector<double> x, double q) {
  if (x.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(x.begin(), x.end());
  return x[std::min(x.size() - 1, static_cast<size_t>(q * x.size()))];
}

// The one-sided 95% normal quantile.
constexpr double kZ95 = 1.645;

// The order statistic that is at least the q-quantile with 95% confidence
// (binomial, normal approximation). A bound set at the plain quantile of
// the held-out errors covers fewer than q of other points' about as often
// as not, and less still once the best of several fits is kept; the
// confidence margin is what other sources need.
double UpperQuantile(std::vector<double> x, double q) {
  if (x.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(x.begin(), x.end());
  const double n = static_cast<double>(x.size());
  const double rank = q * n + kZ95 * std::sqrt(n * q * (1 - q));
  return x[std::min(x.size() - 1, static_cast<size_t>(std::ceil(rank)))];
}

// An answer is no more precise than the float32 distances the index stores
// and the arithmetic on them: on a surface where the refined answers are
// exact (a sphere's traces), the held-out errors are rounding, up to a few
// 1e-6 of the distance, and a quantile of them is no bound for other
// points. So no bound is below this share of the largest distance of its
// bin (0.001%: far below any error target).
constexpr double kRelativePrecision = 1e-5;

// The largest distance of answer bin `b` for scale length L: its upper edge,
// or for the last, open bin the largest answer measured in it.
double BinReach(int b, double scale_length, double largest_in_last) {
  return b + 1 < index::kAccuracyBins ? index::kAccuracyBinUpper[b] * scale_length
                                      : largest_in_last;
}

// Quantiles by bin, at least the precision floor; a bin without errors takes
// the larger bound of its nearest measured neighbours (bounds are not meant
// to be exact there, only not vacuous).
void FillBounds(const std::vector<double> (&errors)[index::kAccuracyBins], double quantile,
                double scale_length, double largest_in_last, float* out) {
  double q[index::kAccuracyBins];
  for (int b = 0; b < index::kAccuracyBins; ++b) {
    q[b] = UpperQuantile(errors[b], quantile);
    if (!std::isnan(q[b])) {
      q[b] = std::max(q[b], kRelativePrecision * BinReach(b, scale_length, largest_in_last));
    }
  }
  for (int b = 0; b < index::kAccuracyBins; ++b) {
    if (!std::isnan(q[b])) {
      out[b] = static_cast<float>(q[b]);
      continue;
    }
    double fill = 0;
    for (int o = b - 1; o >= 0; --o) {
      if (!std::isnan(q[o])) {
        fill = std::max(fill, q[o]);
        break;
      }
    }
    for (int o = b + 1; o < index::kAccuracyBins; ++o) {
      if (!std::isnan(q[o])) {
        fill = std::max(fill, q[o]);
        break;
      }
    }
    out[b] = static_cast<float>(fill);
  }
}

double Rms(const std::vector<double>& x) {
  double sum = 0;
  for (double e : x) sum += e * e;
  return x.empty() ? 0 : std::sqrt(sum / x.size());
}

// An O(1) answer's absolute error, its spread and its distance.
struct SpreadSample {
  double error, spread, distance;
};

// Per bin (see Calibration): epsilon and factor; a bin without pairs takes
// the fit of its nearest measured neighbour (below first), like FillBounds.
// A bin whose best median bound is no smaller than its constant bound
// `constant[b]` keeps the constant one (factor 0): at the same confidence,
// the per-pair bounds pay for their spread's tail with a larger factor, and
// on a coarse index that can outweigh what they save.
void FitSpreadBounds(const std::vector<SpreadSample> (&samples)[index::kAccuracyBins],
                     double quantile, const float* constant, float* epsilon, float* factor) {
  bool fitted[index::kAccuracyBins] = {};
  for (int b = 0; b < index::kAccuracyBins; ++b) {
    epsilon[b] = 0;
    factor[b] = 0;
    double best_median = std::numeric_limits<double>::infinity();
    for (int e = -12; e <= -4; ++e) {
      const double eps = std::ldexp(1.0, e);
      std::vector<double> ratio, bound;
      for (const SpreadSample& x : samples[b]) {
        // An answer of 0 (two points lifted onto each other) has no scale.
        if (x.spread + eps * x.distance > 0)
          ratio.push_back(x.error / (x.spread + eps * x.distance));
      }
      if (ratio.empty()) break;
      const double k = UpperQuantile(ratio, quantile);
      for (const SpreadSample& x : samples[b]) bound.push_back(k * (x.spread + eps * x.distance));
      const double median = Quantile(bound, 0.5);
      if (std::isfinite(k) && median < best_median) {
        best_median = median;
        epsilon[b] = static_cast<float>(eps);
        factor[b] = static_cast<float>(k);
        fitted[b] = true;
      }
    }
    if (fitted[b] && !(best_median < constant[b])) {
      epsilon[b] = 0;
      factor[b] = 0;
    }
  }
  for (int b = 0; b < index::kAccuracyBins; ++b) {
    if (fitted[b]) continue;
    for (int step = 1; step < index::kAccuracyBins; ++step) {
      const int o = b - step >= 0 && fitted[b - step] ? b - step : b + step;
      if (o < index::kAccuracyBins && fitted[o]) {
        epsilon[b] = epsilon[o];
        factor[b] = factor[o];
        break;
      }
    }
  }
}

// fn(k) for k in [0, n) on `threads` threads (0: all), each k once.
void ForEachPair(size_t n, int threads, const std::function<void(size_t)>& fn) {
  const int count =
      std::min<int>(common::ThreadCount(threads), static_cast<int>(std::max<size_t>(n, 1)));
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t k = next++; k < n; k = next++) fn(k);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < count; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

}  // namespace

// Vertex pairs are among the file's vertices, not the split's midpoints:
// those are flat points, and bounds fitted on them would be too tight for
// the corners callers ask about. The split is flat, so the mesh before it
// is the same surface: its exact propagations, most of a calibration's
// time, give the same distances over several times fewer vertices.
absl::StatusOr<std::vector<ExactPair>> HeldOutPairs(const mesh::Mesh& mesh,
                                                    const index::Index& index,
                                                    PairOptions options) {
  options.vertex_limit = index.num_vertices() - index.split_vertices();
  if (!index.split().split()) return DrawPairs(mesh, index.num_samples(), options);
  GEODEX_ASSIGN_OR_RETURN(const std::optional<index::CoarseSurface> surface,
                          index::CoarseSurfaceOf(mesh, index.split(), index.split_vertices()));
  const mesh::Mesh& coarse = surface->mesh;
  std::vector<ExactPair> pairs = DrawPairs(coarse, index.num_samples(), options);
  const query::InputIds ids(index);
  for (ExactPair& pair : pairs) {
    GEODEX_ASSIGN_OR_RETURN(pair.p, ids.CoarseToInternal(pair.p));
    GEODEX_ASSIGN_OR_RETURN(pair.q, ids.CoarseToInternal(pair.q));
  }
  return pairs;
}

UniformConfidence UniformConfidenceOf(const std::vector<double>& errors,
                                      const std::vector<int32_t>& source,
                                      const std::vector<double>& far) {
  UniformConfidence c;
  // Per source: the sum of squared errors and the count.
  std::vector<std::pair<double, int64_t>> by_source;
  for (size_t k = 0; k < errors.size(); ++k) {
    const size_t s = static_cast<size_t>(source[k]);
    if (s >= by_source.size()) by_source.resize(s + 1, {0.0, 0});
    by_source[s].first += errors[k] * errors[k];
    ++by_source[s].second;
  }
  std::vector<double> mse;
  for (const auto& [sum, count] : by_source) {
    if (count > 0) mse.push_back(sum / count);
  }
  if (!mse.empty()) {
    const double n = static_cast<double>(mse.size());
    double mean = 0;
    for (double x : mse) mean += x;
    mean /= n;
    double var = 0;
    for (double x : mse) var += (x - mean) * (x - mean);
    // One source says nothing of the spread: no margin can be had from it.
    const double se = mse.size() > 1 ? std::sqrt(var / (n - 1) / n) : mean;
    c.rms_upper = std::sqrt(mean + kZ95 * se);
  }
  c.far_p99_upper = P99UpperLimit(far);
  return c;
}

double P99UpperLimit(std::vector<double> x) {
  return x.empty() ? 0 : UpperQuantile(std::move(x), 0.99);
}

namespace {

absl::Status CheckBuiltFrom(const mesh::Mesh& mesh, const index::Index& index) {
  if (index.num_vertices() != mesh.num_vertices() || index.num_faces() != mesh.num_faces()) {
    return absl::FailedPreconditionError("the index was not built from this mesh");
  }
  return absl::OkStatus();
}

// The answers of the uncalibrated index to one held-out pair, which the
// bounds are fitted on.
struct Answers {
  absl::StatusOr<double> unfolded = absl::UnknownError("");
  absl::StatusOr<double> walked = absl::UnknownError("");
  bool wraps = false;
  double spread = 0;
};

// Fills the answers of the uncalibrated `engine` to pairs [known, size) of
// `pairs`, each in its own slot: the calibration does not depend on the
// thread count.
void AnswerUncalibrated(const query::QueryEngine& engine, const std::vector<ExactPair>& pairs,
                        int threads, size_t known, std::vector<Answers>& answers) {
  const query::DistanceOptions pure{.near_pairs = query::NearPairs::kUnfold};
  ForEachPair(pairs.size() - known, threads, [&](size_t j) {
    const size_t k = known + j;
    Answers& a = answers[k];
    a.unfolded = engine.Distance(pairs[k].p, pairs[k].q, pure);
    a.walked = engine.WalkedDistance(pairs[k].p, pairs[k].q, &a.wraps);
    if (a.unfolded.ok()) a.spread = engine.UnfoldingSpread(pairs[k].p, pairs[k].q);
  });
}

// The errors of the uncalibrated answers, by answer bin, that the bounds
// are fitted on.
struct UncalibratedErrors {
  std::vector<double> unfold[2][index::kAccuracyBins], trace[4][index::kAccuracyBins];
  std::vector<SpreadSample> spread[2][index::kAccuracyBins];
  double largest_answer = 0;  // of the last, open answer bin
};

UncalibratedErrors UncalibratedErrorsOf(const std::vector<ExactPair>& pairs,
                                        const std::vector<Answers>& answers, double scale) {
  UncalibratedErrors out;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const ExactPair& pair = pairs[k];
    const absl::StatusOr<double>& u = answers[k].unfolded;
    const bool wraps = answers[k].wraps;
    const absl::StatusOr<double>& t = answers[k].walked;
    if (!u.ok()) continue;
    if (std::isfinite(*u)) out.largest_answer = std::max(out.largest_answer, *u);
    if (t.ok() && std::isfinite(*t)) out.largest_answer = std::max(out.largest_answer, *t);
    const int bin = AccuracyBinOf(*u, scale);
    out.unfold[pair.vertices ? 0 : 1][bin].push_back(std::abs(*u - pair.exact));
    out.spread[pair.vertices ? 0 : 1][bin].push_back(
        {std::abs(*u - pair.exact), answers[k].spread, *u});
    if (t.ok()) {
      out.trace[2 * pair.vertices + wraps][AccuracyBinOf(*t, scale)].push_back(
          std::abs(*t - pair.exact));
    }
  }
  return out;
}

// The default answer to every pair, from an engine that has the bounds
// (the default mode uses them to doubt a trace).
absl::StatusOr<std::vector<absl::StatusOr<double>>> DefaultAnswers(
    const index::Index& index, const index::AccuracyRecord& r,
    const index::SpreadBoundRecord& spread, const std::vector<ExactPair>& pairs, int threads) {
  index::IndexData data = index::ToIndexData(index);
  data.accuracy = {r};
  data.spread_bounds = {spread};
  GEODEX_ASSIGN_OR_RETURN(std::string bytes, index::SerializeIndex(data));
  GEODEX_ASSIGN_OR_RETURN(auto calibrated, index::Index::FromBytes(std::move(bytes)));
  GEODEX_ASSIGN_OR_RETURN(auto engine, query::QueryEngine::Create(std::move(calibrated)));
  std::vector<absl::StatusOr<double>> defaults(pairs.size(), absl::UnknownError(""));
  ForEachPair(pairs.size(), threads,
              [&](size_t k) { defaults[k] = engine->Distance(pairs[k].p, pairs[k].q); });
  return defaults;
}

// The relative errors of the default answers, by scale bin, by fixed band
// and over the area-uniform pairs.
struct DefaultErrors {
  std::vector<double> relative[kNumScaleBins], uniform, uniform_far;
  std::vector<double> by_kind[2][kNumScaleBins];  // |relative error|, BinConfidence's kinds
  std::vector<int32_t> uniform_source;
  std::vector<double> band_errors[2][kNumFixedBins], far_errors[2];
};

DefaultErrors DefaultErrorsOf(const std::vector<ExactPair>& pairs,
                              const std::vector<absl::StatusOr<double>>& defaults, double unit) {
  DefaultErrors out;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const ExactPair& pair = pairs[k];
    const absl::StatusOr<double>& d = defaults[k];
    if (!d.ok()) continue;
    const double e = (*d - pair.exact) / pair.exact;
    const int kind = pair.vertices ? BinConfidence::kVertex : BinConfidence::kInterior;
    out.band_errors[kind][FixedBinOf(pair.exact, unit)].push_back(std::abs(e));
    if (pair.uniform && pair.exact >= FixedBinLower(FixedBands::kFarBin) * unit) {
      out.far_errors[kind].push_back(std::abs(e));
    }
    out.relative[pair.bin].push_back(e);
    out.by_kind[pair.vertices ? BinConfidence::kVertex : BinConfidence::kInterior][pair.bin]
        .push_back(std::abs(e));
    if (pair.uniform && !pair.vertices) {
      out.uniform.push_back(e);
      out.uniform_source.push_back(pair.source);
      if (pair.bin == kNumScaleBins - 1) out.uniform_far.push_back(std::abs(e));
    }
  }
  return out;
}

// The figures of the default answers: the record's RMS and p99 by scale
// bin, the confidence limits, the bins' and the fixed bands' p99.
void FillFigures(const DefaultErrors& e, index::AccuracyRecord& r, Calibration& result) {
  for (int b = 0; b < kNumScaleBins; ++b) {
    r.rms[b] = static_cast<float>(Rms(e.relative[b]));
    std::vector<double> abs = e.relative[b];
    for (double& x : abs) x = std::abs(x);
    r.p99[b] = e.relative[b].empty() ? 0 : static_cast<float>(Quantile(abs, 0.99));
  }
  r.uniform_rms = static_cast<float>(Rms(e.uniform));
  r.uniform_far_p99 = e.uniform_far.empty() ? 0 : static_cast<float>(Quantile(e.uniform_far, 0.99));
  result.confidence = UniformConfidenceOf(e.uniform, e.uniform_source, e.uniform_far);
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < kNumScaleBins; ++b) {
      const std::vector<double>& x = e.by_kind[k][b];
      result.bins.pairs[k][b] = static_cast<int32_t>(x.size());
      result.bins.p99[k][b] = x.empty() ? 0 : Quantile(x, 0.99);
      result.bins.p99_upper[k][b] = P99UpperLimit(x);
    }
  }
  FixedBands& bands = result.bands;
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < kNumFixedBins; ++b) {
      bands.pairs[k][b] = static_cast<int32_t>(e.band_errors[k][b].size());
      bands.p99[k][b] = e.band_errors[k][b].empty() ? 0 : Quantile(e.band_errors[k][b], 0.99);
    }
    bands.far_pairs[k] = static_cast<int32_t>(e.far_errors[k].size());
    bands.far_p99[k] = e.far_errors[k].empty() ? 0 : Quantile(e.far_errors[k], 0.99);
    bands.far_p99_upper[k] = P99UpperLimit(e.far_errors[k]);
  }
}

// Calibrate on `pairs` (HeldOutPairs of options.pairs' sources);
// `uncalibrated` holds the answers of a prefix of them, and gets all.
absl::StatusOr<Calibration> CalibrateOn(const mesh::Mesh& mesh,
                                        std::shared_ptr<const index::Index> index,
                                        const std::vector<ExactPair>& pairs,
                                        const CalibrationOptions& options,
                                        std::vector<Answers>* uncalibrated) {
  GEODEX_ASSIGN_OR_RETURN(auto engine, query::QueryEngine::Create(index));
  const double scale = engine->scale_length();
  // Those of the pairs measured before (a sequential calibration's earlier
  // sources) are kept.
  std::vector<Answers>& answers = *uncalibrated;
  const size_t known = answers.size();
  answers.resize(pairs.size());
  AnswerUncalibrated(*engine, pairs, options.pairs.threads, known, answers);
  const UncalibratedErrors u = UncalibratedErrorsOf(pairs, answers, scale);
  index::AccuracyRecord r{};
  r.scale_length = static_cast<float>(scale);
  r.num_sources = options.pairs.num_sources;
  r.num_pairs = static_cast<uint32_t>(pairs.size());
  r.bound_quantile_permille = static_cast<uint32_t>(std::lround(1000 * options.quantile));
  FillBounds(u.unfold[0], options.quantile, scale, u.largest_answer, r.unfold_bound[0]);
  FillBounds(u.unfold[1], options.quantile, scale, u.largest_answer, r.unfold_bound[1]);
  for (int k = 0; k < 4; ++k) {
    FillBounds(u.trace[k], options.quantile, scale, u.largest_answer, r.trace_bound[k]);
  }
  Calibration result;
  for (int k = 0; k < 2; ++k) {
    FitSpreadBounds(u.spread[k], options.quantile, r.unfold_bound[k], result.spread.epsilon[k],
                    result.spread.factor[k]);
  }
  GEODEX_ASSIGN_OR_RETURN(const std::vector<absl::StatusOr<double>> defaults,
                          DefaultAnswers(*index, r, result.spread, pairs, options.pairs.threads));
  result.bands.unit = ScaleLength(mesh.TotalArea(), kFixedUnitSamples);
  const DefaultErrors errors = DefaultErrorsOf(pairs, defaults, result.bands.unit);
  if (errors.uniform.empty()) return absl::InternalError("calibration: no pair could be measured");
  FillFigures(errors, r, result);
  result.record = r;
  return result;
}

}  // namespace

absl::StatusOr<Calibration> Calibrate(const mesh::Mesh& mesh,
                                      std::shared_ptr<const index::Index> index,
                                      const CalibrationOptions& options) {
  GEODEX_RETURN_IF_ERROR(CheckBuiltFrom(mesh, *index));
  GEODEX_ASSIGN_OR_RETURN(const std::vector<ExactPair> pairs,
                          HeldOutPairs(mesh, *index, options.pairs));
  std::vector<Answers> answers;
  return CalibrateOn(mesh, std::move(index), pairs, options, &answers);
}

absl::Status AddCalibration(const mesh::Mesh& mesh, index::IndexData& data,
                            const CalibrationOptions& options, Calibration* out) {
  return AddCalibrationUntil(mesh, data, options, options.pairs.num_sources, nullptr, out);
}

absl::Status AddCalibrationUntil(const mesh::Mesh& mesh, index::IndexData& data,
                                 const CalibrationOptions& options, int32_t max_sources,
                                 const std::function<bool(const Calibration&)>& settled,
                                 Calibration* out) {
  data.accuracy.clear();
  data.spread_bounds.clear();
  GEODEX_ASSIGN_OR_RETURN(std::string bytes, index::SerializeIndex(data));
  GEODEX_ASSIGN_OR_RETURN(std::shared_ptr<const index::Index> index,
                          index::Index::FromBytes(std::move(bytes)));
  GEODEX_RETURN_IF_ERROR(CheckBuiltFrom(mesh, *index));
  CalibrationOptions drawn = options;
  GEODEX_ASSIGN_OR_RETURN(std::vector<ExactPair> pairs, HeldOutPairs(mesh, *index, drawn.pairs));
  std::vector<Answers> answers;
  GEODEX_ASSIGN_OR_RETURN(Calibration calibration,
                          CalibrateOn(mesh, index, pairs, drawn, &answers));
  while (settled != nullptr && drawn.pairs.num_sources < max_sources && !settled(calibration)) {
    // The sources drawn so far keep their pairs; only the new ones propagate.
    PairOptions more = drawn.pairs;
    more.first_source = drawn.pairs.first_source + drawn.pairs.num_sources;
    more.num_sources = std::min(drawn.pairs.num_sources, max_sources - drawn.pairs.num_sources);
    GEODEX_ASSIGN_OR_RETURN(std::vector<ExactPair> added, HeldOutPairs(mesh, *index, more));
    pairs.insert(pairs.end(), added.begin(), added.end());
    drawn.pairs.num_sources += more.num_sources;
    GEODEX_ASSIGN_OR_RETURN(calibration, CalibrateOn(mesh, index, pairs, drawn, &answers));
  }
  data.accuracy = {calibration.record};
  data.spread_bounds = {calibration.spread};
  if (out != nullptr) *out = std::move(calibration);
  return absl::OkStatus();
}

std::string CalibrationText(const index::AccuracyRecord& r) {
  std::string out = absl::StrFormat(
      "accuracy_sources = %d\naccuracy_pairs = %d\nscale_length = %.6g\n"
      "accuracy_uniform_rms = %.6g\naccuracy_uniform_far_p99 = %.6g\n",
      r.num_sources, r.num_pairs, r.scale_length, r.uniform_rms, r.uniform_far_p99);
  static const char* const kBin[kNumScaleBins] = {"below_L", "L_3L", "3L_10L", "beyond_10L"};
  for (int b = 0; b < kNumScaleBins; ++b) {
    out += absl::StrFormat("accuracy_rms_%s = %.6g\naccuracy_p99_%s = %.6g\n", kBin[b], r.rms[b],
                           kBin[b], r.p99[b]);
  }
  return out;
}

}  // namespace geodex::validation
