#include "server/convert/convert_options.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::server {
namespace {

absl::StatusOr<query::NearPairs> NearPairsFor(const ModelConfig& config, int requested,
                                              bool exact_requested) {
  if (!v1::NearPairs_IsValid(requested)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("near_pairs has the unknown value %d", requested));
  }
  if (exact_requested && requested != v1::NEAR_PAIRS_UNSPECIFIED &&
      requested != v1::NEAR_PAIRS_EXACT) {
    return absl::InvalidArgumentError(
        absl::StrFormat("exact_near_pairs contradicts near_pairs = %s",
                        v1::NearPairs_Name(static_cast<v1::NearPairs>(requested))));
  }
  if (exact_requested) return query::NearPairs::kExact;
  switch (static_cast<v1::NearPairs>(requested)) {
    case v1::NEAR_PAIRS_PATH:
      return query::NearPairs::kPath;
    case v1::NEAR_PAIRS_UNFOLD:
      return query::NearPairs::kUnfold;
    case v1::NEAR_PAIRS_EXACT:
      return query::NearPairs::kExact;
    default:
      break;
  }
  if (config.exact_near_pairs()) return query::NearPairs::kExact;
  if (config.unfold_near_pairs()) return query::NearPairs::kUnfold;
  return query::NearPairs::kPath;
}

}  // namespace

DistanceChoice DistanceChoice::Of(const v1::DistanceRequest& r) {
  return {r.near_pairs(), r.exact_near_pairs(), r.tolerance(), r.error_bounds()};
}

DistanceChoice DistanceChoice::Of(const v1::DistanceBatch& r) {
  return {r.near_pairs(), r.exact_near_pairs(), r.tolerance(), r.error_bounds()};
}

DistanceChoice DistanceChoice::Of(const v1::MatrixRequest& r) {
  return {r.near_pairs(), false, r.tolerance(), r.error_bounds()};
}

absl::StatusOr<query::DistanceOptions> DistanceOptionsFor(const ModelConfig& config,
                                                          const DistanceChoice& choice) {
  query::DistanceOptions options;
  GEODEX_ASSIGN_OR_RETURN(options.near_pairs,
                          NearPairsFor(config, choice.near_pairs, choice.exact_near_pairs));
  const double tolerance = choice.tolerance;
  if (!(tolerance >= 0) || !std::isfinite(tolerance)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tolerance must be finite and >= 0, not %g", tolerance));
  }
  options.tolerance = tolerance > 0 ? tolerance : config.tolerance();
  return options;
}

absl::StatusOr<query::ExpMapOptions> ExpMapOptionsFor(const ModelConfig& config,
                                                      const v1::ExpMapRequest& request) {
  query::ExpMapOptions options;
  options.radius = request.radius();
  const auto& direction = request.reference_direction().xyz();
  if (direction.size() == 3) {
    options.reference_direction = mesh::Vec3(direction[0], direction[1], direction[2]);
  } else if (!direction.empty()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "reference_direction: give one direction (3 numbers), got %d numbers", direction.size()));
  }
  GEODEX_ASSIGN_OR_RETURN(options.distance,
                          DistanceOptionsFor(config, {.near_pairs = request.near_pairs(),
                                                      .tolerance = request.tolerance()}));
  return options;
}

absl::StatusOr<int32_t> PathCorridorFor(const ModelConfig& config, const v1::PathRequest& request) {
  if (request.exact_corridor() > kMaxPathCorridor) {
    return absl::InvalidArgumentError(absl::StrFormat("exact_corridor %d exceeds %d",
                                                      request.exact_corridor(), kMaxPathCorridor));
  }
  if (request.exact_corridor() > 0) return static_cast<int32_t>(request.exact_corridor());
  return std::clamp<int32_t>(config.exact_path_corridor(), 0, kMaxPathCorridor);
}

}  // namespace geodex::server
