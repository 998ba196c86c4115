#pragma once

// The accuracy calibration of an index (index::AccuracyRecord): the builder
// measures the answers of the index it has just made against exact
// propagations from held-out surface points (area-uniform points and
// uniformly drawn vertices, never chosen for being samples; a seed of their
// own), and stores, per distance bin and kind of answer, the quantile of the
// absolute errors that becomes every answer's error bound, with the relative
// error of the default answer by scale.
//
// Lives above core/query and below core/build: it needs an index and the
// query engine that answers from it, and the build's rounds read it.
//
// Thread safety: reentrant.

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/validation/pair_sampling.h"

namespace geodex::validation {

struct CalibrationOptions {
  // Held-out pairs. The default seed differs from the accuracy harness's, so
  // that the harness measures on other points.
  // Many sources with few targets each: errors depend on where the source
  // lies, and the bounds must hold for sources not seen here.
  PairOptions pairs = {
      .num_sources = 64, .uniform_points = 60, .per_bin_points = 15, .seed = 0x6a09e667f3bcc909ULL};
  // The bounds are the 95% upper confidence limit of this quantile of the
  // absolute errors in their bin.
  double quantile = 0.995;
};

// How far the held-out figures of the area-uniform pairs can be trusted:
// one-sided 95% upper confidence limits of their relative RMS and of their
// p99 beyond 10L. A builder that stops on the measured figures alone stops
// as often as not just under a target that other held-out points then miss;
// stopping on these limits leaves the margin that sampling noise needs.
struct UniformConfidence {
  // The pairs of one source err together (its point may lie in a bad
  // geodesic triangle), so the sources, not the pairs, are the independent
  // draws: sqrt of the mean of the sources' mean squared errors plus 1.645
  // standard errors of that mean.
  double rms_upper = 0;
  // The order statistic that is at least the 99th percentile with 95%
  // confidence (binomial, normal approximation).
  double far_p99_upper = 0;
};

// The default answer's relative error in each scale bin, vertex and
// interior pairs apart (pair_sampling.h: vertex pairs are mesh vertices of
// the file, interior pairs points inside faces), with the 95% upper
// confidence limit of each p99 (the order statistic of
// UniformConfidence::far_p99_upper). What a target-error build judges every
// bin by (target_error.h).
struct BinConfidence {
  static constexpr int kVertex = 0, kInterior = 1;
  // [kind][bin]; a bin without pairs has 0 pairs and 0 figures.
  double p99[2][kNumScaleBins] = {};
  double p99_upper[2][kNumScaleBins] = {};
  int32_t pairs[2][kNumScaleBins] = {};
};

// The default answer's relative error in the bins of a unit fixed by the
// surface (pair_sampling.h: L1000), vertex and interior pairs apart: what a
// user gets at each distance, whatever m. The far band, pairs at least
// 8 L1000 apart, holds only undirected draws (area-uniform interior
// points; uniformly drawn vertices), and its p99 carries its 95% upper
// confidence limit: what the default target judges (target_error.h).
struct FixedBands {
  static constexpr int kFarBin = 5;  // [8, 16) L1000 and beyond
  double unit = 0;                   // L1000, in mesh units
  // [kind][bin] over every pair (uniform and drawn in a bin); a bin without
  // pairs has 0 pairs and 0 figures.
  double p99[2][kNumFixedBins] = {};
  int32_t pairs[2][kNumFixedBins] = {};
  double far_p99[2] = {};
  double far_p99_upper[2] = {};
  int32_t far_pairs[2] = {};
};

// What a calibration measures: the record of the constant bounds and
// figures, the per-pair bounds of O(1) answers fitted on the same pairs
// (index::SpreadBoundRecord: per bin, epsilon from a fixed grid of powers
// of two, 2^-12 .. 2^-4, whichever makes the bin's median bound smallest),
// and the confidence limits of the uniform figures.
struct Calibration {
  index::AccuracyRecord record{};
  index::SpreadBoundRecord spread{};
  UniformConfidence confidence;
  BinConfidence bins;
  FixedBands bands;
};

// Measures `index` (built from `mesh`) and returns its calibration.
// Errors: FailedPrecondition when the index was not built from this mesh or
// has no triangles; Internal when no pair could be measured.
absl::StatusOr<Calibration> Calibrate(const mesh::Mesh& mesh,
                                      std::shared_ptr<const index::Index> index,
                                      const CalibrationOptions& options = {});

// `data` with its calibration (the accuracy and spread-bound records) added,
// replacing any, for writing; with `calibration`, all that it measured.
absl::Status AddCalibration(const mesh::Mesh& mesh, index::IndexData& data,
                            const CalibrationOptions& options = {},
                            Calibration* calibration = nullptr);

// AddCalibration as a sequential measurement: options.pairs.num_sources
// held-out sources first, then as many again (the ones drawn keep their
// pairs; every answer is measured again on all of them) until `settled`
// says the calibration so far decides what it is measured for, or
// `max_sources` are drawn. Sources, not pairs, are the independent draws
// (UniformConfidence), so each doubling narrows the confidence limits by
// about 1/sqrt(2). `calibration` gets the last measurement.
absl::Status AddCalibrationUntil(const mesh::Mesh& mesh, index::IndexData& data,
                                 const CalibrationOptions& options, int32_t max_sources,
                                 const std::function<bool(const Calibration&)>& settled,
                                 Calibration* calibration = nullptr);

// The held-out pairs Calibrate measures `index` (built from `mesh`) on, in
// the index's internal ids: DrawPairs with `options`, vertex pairs among
// the vertices before the long-edge split. On an index of a split mesh the
// pairs are drawn, and their exact distances propagated, on the mesh before
// the split (the index's coarse faces over its first vertices). Errors:
// InvalidArgument when those do not make a mesh; Internal when a point
// finds no piece of its face. Exposed for tests.
absl::StatusOr<std::vector<ExactPair>> HeldOutPairs(const mesh::Mesh& mesh,
                                                    const index::Index& index,
                                                    PairOptions options);

// The upper confidence limits of UniformConfidence for relative errors
// `errors` drawn from sources `source` (parallel arrays), and for the
// absolute relative errors `far` of the pairs beyond 10L. Exposed for tests.
UniformConfidence UniformConfidenceOf(const std::vector<double>& errors,
                                      const std::vector<int32_t>& source,
                                      const std::vector<double>& far);

// The order statistic of `x` (absolute errors) that is at least their 99th
// percentile with 95% confidence (binomial, normal approximation); 0 for
// no errors. Exposed for tests.
double P99UpperLimit(std::vector<double> x);

// "key = value" lines of a calibration, for build reports.
std::string CalibrationText(const index::AccuracyRecord& record);

}  // namespace geodex::validation
