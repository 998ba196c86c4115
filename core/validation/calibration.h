#pragma once

// The accuracy calibration of an index (index::AccuracyRecord): the builder
// measures the answers of the index it has just made against exact
// propagations from held-out surface points (area-uniform points and
// uniformly drawn vertices, never chosen for being samples; a seed of their
// own), and stores, per distance bin and kind of answer, the quantile of the
// absolute errors that becomes every answer's error bound, with the relative
// error of the default answer by scale.
//
// Lives above core/builder and core/query: it needs both an index and the
// query engine that answers from it.
//
// Thread safety: reentrant.

#include <cstdint>
#include <memory>

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
  // The bounds are this quantile of the absolute errors in their bin.
  double quantile = 0.995;
};

// Measures `index` (built from `mesh`) and returns its calibration.
// Errors: FailedPrecondition when the index was not built from this mesh or
// has no triangles; Internal when no pair could be measured.
absl::StatusOr<index::AccuracyRecord> Calibrate(const mesh::Mesh& mesh,
                                                std::shared_ptr<const index::Index> index,
                                                const CalibrationOptions& options = {});

// `data` with its calibration added (replacing any), for writing.
absl::Status AddCalibration(const mesh::Mesh& mesh, index::IndexData& data,
                            const CalibrationOptions& options = {});

// "key = value" lines of a calibration, for build reports.
std::string CalibrationText(const index::AccuracyRecord& record);

}  // namespace geodex::validation
