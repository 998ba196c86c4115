#include "server/config/limits.h"

#include "absl/strings/str_format.h"

namespace geodex::server {

absl::Status CheckPairsPerMessage(const ServiceLimits& limits, int64_t pairs) {
  if (pairs <= limits.max_pairs_per_message) return absl::OkStatus();
  return absl::ResourceExhaustedError(
      absl::StrFormat("%d pairs exceed the limit of %d per message (max_pairs_per_message)", pairs,
                      limits.max_pairs_per_message));
}

absl::Status CheckMatrixCells(const ServiceLimits& limits, int64_t sources, int64_t targets) {
  // Divides rather than multiplies: sources x targets may overflow.
  if (sources <= 0 || targets <= limits.max_matrix_cells / sources) return absl::OkStatus();
  return absl::ResourceExhaustedError(
      absl::StrFormat("%d sources x %d targets exceed the limit of %d cells (max_matrix_cells)",
                      sources, targets, limits.max_matrix_cells));
}

absl::Status CheckFieldSources(const ServiceLimits& limits, int64_t sources) {
  if (sources <= limits.max_field_sources) return absl::OkStatus();
  return absl::ResourceExhaustedError(absl::StrFormat(
      "%d sources exceed the limit of %d (max_field_sources)", sources, limits.max_field_sources));
}

// `limits` keeps the signature of the other checks; the propagation's message
// already names the count it stopped at.
absl::Status FieldVerticesExceeded([[maybe_unused]] const ServiceLimits& limits,
                                   const absl::Status& status) {
  return absl::ResourceExhaustedError(
      absl::StrFormat("%s, the limit (max_field_vertices)", status.message()));
}

absl::Status CheckPathPairs(const ServiceLimits& limits, int64_t pairs) {
  if (pairs <= limits.max_path_pairs) return absl::OkStatus();
  return absl::ResourceExhaustedError(
      absl::StrFormat("%d pairs exceed the limit of %d per Path call (max_path_pairs)", pairs,
                      limits.max_path_pairs));
}

absl::Status CheckLocatePositions(const ServiceLimits& limits, int64_t positions) {
  if (positions <= limits.max_locate_positions) return absl::OkStatus();
  return absl::ResourceExhaustedError(
      absl::StrFormat("%d positions exceed the limit of %d per Locate call (max_locate_positions)",
                      positions, limits.max_locate_positions));
}

absl::Status CheckConcurrentStreams(const ServiceLimits& limits, int64_t running) {
  if (running < limits.max_concurrent_streams) return absl::OkStatus();
  return absl::ResourceExhaustedError(
      absl::StrFormat("%d streaming calls already running (max_concurrent_streams)", running));
}

}  // namespace geodex::server
