#pragma once

// What a target-error build asks of an index, how to tell from its
// calibration whether the index meets it, and how many samples the next
// round should have when it does not (the rounds themselves:
// core/builder/build_rounds.h).
//
// A target E asks of the default answer (near pairs refined), on held-out
// pairs (calibration.h: sources the build never sampled):
//   - relative RMS over area-uniform interior pairs <= E;
//   - p99 of |relative error| <= 2E in each bin below 3L (d < L, L-3L);
//   - p99 <= 4E in each bin at or beyond 3L (3L-10L, >= 10L);
// each bin for vertex pairs and interior pairs apart. Every figure is judged
// by its 95% upper confidence limit, not by the measured value: an index
// that only just meets a target on the held-out points misses it on others
// as often as not.
//
// How many samples a target needs is predicted from how the figures fall
// with m. The O(1) answer's absolute error falls about as 1/m, but a bin at
// a fixed multiple of L = sqrt(2A / (sqrt(3) m)) moves closer as m grows, so
// its relative error falls more slowly; measured from m = 500 to 4000 on
// the shared meshes (tests/bench/README.md, "Error falls with m"), the
// uniform RMS falls about as m^-0.7 and a bin's p99 as m^-0.6. Between two
// rounds a bin's p99 is too noisy to measure its own rate (a few sources
// make it; it even rises from one m to the next on some meshes), so the
// prediction uses those rates.
//
// Thread safety: pure functions.

#include <cstdint>
#include <span>
#include <string>

#include "core/validation/calibration.h"
#include "core/validation/pair_sampling.h"

namespace geodex::validation {

// The target of a build asked for no sample count.
inline constexpr double kDefaultTargetError = 0.005;
// The default cap on m: its m x m float matrix is 256 MB.
inline constexpr int32_t kDefaultMaxSamples = 8000;
// The most bytes a target-error build's index may take. A server holds many
// models, so m stops growing where the next index would not fit; the
// sample matrix (m (m - 1) / 2 floats) alone is 64 MiB near m = 5,800.
inline constexpr int64_t kMaxIndexBytes = int64_t{64} << 20;

// The largest m whose index fits in `budget` bytes, predicted from an index
// of `samples` samples that takes `bytes`: the sample matrix grows as m^2,
// the rest (the refined mesh, vertex records, calibration) at most in
// proportion to m.
int32_t SamplesWithinBytes(int64_t budget, int32_t samples, int64_t bytes);

// The checks: 0 the uniform RMS, then 1 + kind * kNumScaleBins + bin
// (BinConfidence's kinds and bins).
inline constexpr int kNumTargetChecks = 1 + 2 * kNumScaleBins;
// "uniform RMS", "vertex d<L p99", ..., "interior >=10L p99".
std::string TargetCheckName(int check);
// The limit of check `check` for target E: E, 2E or 4E.
double TargetLimit(int check, double target);

// One round's figures, as a work directory keeps them between the steps of
// a distributed build.
struct TargetFigures {
  int32_t samples = 0;  // m of the index measured
  double measured[kNumTargetChecks] = {};
  double upper[kNumTargetChecks] = {};   // 95% upper confidence limits
  int32_t pairs[kNumTargetChecks] = {};  // 0: the bin had no pair (not judged)
};
TargetFigures FiguresOf(const Calibration& calibration, int32_t samples);

// Every check with pairs has upper <= limit.
bool TargetMet(const TargetFigures& figures, double target);
// The check with the largest upper / limit among those with pairs.
int WorstCheck(const TargetFigures& figures, double target);
// One line: m, then each check's measured (upper) / limit, unmet ones marked.
std::string FiguresText(const TargetFigures& figures, double target);

struct PredictionOptions {
  // Aim each check's upper limit at this share of its limit, for the noise
  // of the next round's measurement.
  double aim = 0.9;
  // The next m is at least min_growth and at most max_growth times the last.
  double min_growth = 1.2;
  double max_growth = 3.0;
};

// The m of the next round after `rounds` (oldest first, at least one): for
// each unmet check of the last round, the m at which its upper limit would
// reach aim x limit if it fell as m^-0.7 (the RMS) or m^-0.6 (a bin's p99)
// from there; the largest of those, within the growth bounds and at most
// `cap`.
int32_t PredictSamples(std::span<const TargetFigures> rounds, double target, int32_t cap,
                       const PredictionOptions& options = {});

}  // namespace geodex::validation
