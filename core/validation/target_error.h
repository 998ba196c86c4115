#pragma once

// What a target-error build asks of an index, how to tell from its
// calibration whether the index meets it, and how many samples the next
// round should have when it does not (the rounds themselves:
// core/build/build_rounds.h).
//
// A target E asks of the default answer, on held-out pairs (calibration.h:
// sources the build never sampled), in units fixed by the surface
// (L1000 = sqrt(2A / (sqrt(3) 1000)), pair_sampling.h), not by m:
//   - relative RMS over area-uniform interior pairs <= E;
//   - p99 of |relative error| <= 4E over the undirected pairs at least
//     8 L1000 apart, vertex pairs and interior pairs apart.
// Both are what the O(1) answer controls: it errs about the same at every
// distance and less as m grows, so its relative error at a fixed distance
// falls with m and every mesh meets the target at some m. Closer pairs
// are refined (walked, or exact where no walk vouches for one) or, between
// 3L and 8 L1000, answered in O(1) at an error no m the budget allows
// brings under 4E (tests/bench, "Levels of samples"); the calibration
// measures them by fixed band, for the report, and does not judge them.
// Every judged figure is its 95% upper confidence limit, not the measured
// value: an index that only just meets a target on the held-out points
// misses it on others as often as not.
//
// How many samples a target needs is predicted from how the figures fall
// with m: the uniform RMS about as m^-0.7 (tests/bench, "Error falls with
// m"), the far band's p99 about as m^-0.8 (its pairs stay put while the
// samples close in: a statue's 8-16 L1000 p99 fell from 3.45% at m = 1,210
// to 1.26% at m = 4,247).
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
// The default cap on m: its coded matrix (1.5 m (m - 1) bytes) is 96 MB.
inline constexpr int32_t kDefaultMaxSamples = 8000;
// The most bytes a target-error build's index may take by default. A server
// holds many models, so m stops growing where the next index would not
// fit; the coded matrix alone is 32 MiB near m = 4,730.
inline constexpr int64_t kMaxIndexBytes = int64_t{32} << 20;

// The largest m whose index fits in `budget` bytes, predicted from an index
// of `samples` samples that takes `bytes`: the coded matrix grows as
// 1.5 m (m - 1) bytes, the rest (the split mesh, vertex records, calibration)
// at most in proportion to m.
int32_t SamplesWithinBytes(int64_t budget, int32_t samples, int64_t bytes);

// The checks: 0 the uniform RMS, 1 the vertex pairs' p99 and 2 the interior
// pairs' p99 at least 8 L1000 apart.
inline constexpr int kNumTargetChecks = 3;
// "uniform RMS", "vertex >=8 L1000 p99", "interior >=8 L1000 p99".
std::string TargetCheckName(int check);
// The limit of check `check` for target E: E for the RMS, 4E for a p99.
double TargetLimit(int check, double target);

// One round's figures, as a work directory keeps them between the steps of
// a distributed build: the judged checks, and the band p99s (measured, not
// judged) by fixed bin, [kind][bin] as FixedBands.
struct TargetFigures {
  int32_t samples = 0;  // m of the index measured
  double measured[kNumTargetChecks] = {};
  double upper[kNumTargetChecks] = {};   // 95% upper confidence limits
  int32_t pairs[kNumTargetChecks] = {};  // 0: no pair (not judged)
  double band_p99[2][kNumFixedBins] = {};
  int32_t band_pairs[2][kNumFixedBins] = {};
  double unit = 0;  // L1000
};
TargetFigures FiguresOf(const Calibration& calibration, int32_t samples);

// Every check with pairs has upper <= limit.
bool TargetMet(const TargetFigures& figures, double target);
// The check with the largest upper / limit among those with pairs.
int WorstCheck(const TargetFigures& figures, double target);
// That largest upper / limit: how far a round is from the target (<= 1:
// met). A round is closer than another when this is smaller.
double Distance(const TargetFigures& figures, double target);
// Whether a round's figures settle it, the stopping rule of its sequential
// validation (calibration.h, AddCalibrationUntil): settled when some check
// misses its limit beyond doubt (its lower confidence limit, the upper one
// mirrored about the measured figure, is over the limit), or when every
// check's upper limit is at most kSettledShare of its limit. Between the two
// the round draws more held-out sources: an index that only just meets its
// target on some sources misses it on others about as often, and a round
// that only just misses it may meet it once the limits narrow, which costs
// far less than another round.
inline constexpr double kSettledShare = 0.9;
bool TargetSettled(const TargetFigures& figures, double target);
// One line: m, then each check's measured (upper) / limit, unmet ones marked.
std::string FiguresText(const TargetFigures& figures, double target);
// One line: the band p99s by fixed bin, vertex / interior.
std::string BandsLine(const TargetFigures& figures);
// "key = value" lines of the bands, for build reports: band_unit (L1000),
// band_refined_below (kRefineScale L of an index of scale length
// `scale_length`, in L1000: the answers below it are walked or exact, the
// others O(1)), then band_p99_<vertex|interior>_<bin> and
// band_pairs_<kind>_<bin>, bins 0_0.5, 0.5_1, ..., 8_16, 16_inf, then each
// judged check as check_<uniform_rms|vertex_far_p99|interior_far_p99> =
// "measured upper95 pairs" (the report's verdict reads these).
std::string BandsText(const TargetFigures& figures, double scale_length);

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
// reach aim x limit if it fell as m^-0.7 (the RMS) or m^-0.8 (a p99) from
// there; the largest of those, within the growth bounds and at most `cap`.
int32_t PredictSamples(std::span<const TargetFigures> rounds, double target, int32_t cap,
                       const PredictionOptions& options = {});

}  // namespace geodex::validation
