#include "core/validation/target_error.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/validation/calibration.h"

namespace geodex::validation {

absl::StatusOr<TargetErrorResult> BuildForTargetError(const mesh::Mesh& mesh,
                                                      builder::BuildOptions build,
                                                      const TargetErrorOptions& options,
                                                      const builder::RepairRecord& repair) {
  if (!(options.target_rms > 0) || !(options.growth > 1)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the target error must be > 0 and the growth > 1 (got %g, %g)",
                        options.target_rms, options.growth));
  }
  int32_t referenced = 0;
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) referenced += mesh.IsReferenced(v);
  // Samples are vertices: without the flat refinement the mesh's own
  // vertices bound m (by default half of them); with it, midpoints make room
  // for more.
  const int32_t bound = build.refine_long_edges ? kDefaultMaxSamples : referenced;
  const int32_t default_cap =
      build.refine_long_edges ? kDefaultMaxSamples : std::max(3, referenced / 2);
  const int32_t cap =
      std::min(bound, options.max_samples > 0 ? options.max_samples
                                              : std::min(default_cap, kDefaultMaxSamples));
  build.num_samples = std::min(std::max(build.num_samples, 3), cap);
  TargetErrorResult result;
  for (int32_t round = 0;; ++round) {
    builder::BuildSummary summary;
    GEODEX_ASSIGN_OR_RETURN(
        const builder::PreparedMesh prepared,
        builder::PrepareMesh(mesh, repair, build.num_samples, build.refine_long_edges));
    GEODEX_ASSIGN_OR_RETURN(index::IndexData data,
                            builder::BuildPreparedIndex(prepared, build, &summary));
    CalibrationOptions calibration;
    calibration.pairs.threads = build.threads;
    calibration.pairs.num_sources = options.validation_sources;
    UniformConfidence confidence;
    GEODEX_RETURN_IF_ERROR(AddCalibration(prepared.mesh, data, calibration, &confidence));
    const index::AccuracyRecord& r = data.accuracy[0];
    const TargetErrorRound done{static_cast<int32_t>(data.samples.size()), r.uniform_rms,
                                r.uniform_far_p99, confidence.rms_upper, confidence.far_p99_upper};
    result.rounds.push_back(done);
    if (options.round_done) options.round_done(round, done);
    result.data = std::move(data);
    result.summary = summary;
    result.reached =
        done.rms_upper <= options.target_rms && done.far_p99_upper <= 4 * options.target_rms;
    if (result.reached || build.num_samples >= cap) break;
    build.num_samples =
        std::min(cap, static_cast<int32_t>(std::ceil(build.num_samples * options.growth)));
  }
  return result;
}

}  // namespace geodex::validation
