#pragma once

// What a request asks of the engine, as core options: the request's choices
// where it makes them, else the defaults of the model's configuration
// (server/config/model_config.proto). The sibling of server/convert/convert.h, which reads
// the request's points and writes the answers.
//
// Errors: InvalidArgument for an unknown or contradictory choice, naming the
// field as the request spells it.
//
// Thread safety: pure functions.

#include <cstdint>

#include "absl/status/statusor.h"
#include "core/query/query_types.h"
#include "geodex/v1/geodex.pb.h"
#include "server/config/model_config.pb.h"

namespace geodex::server {

// What a distance request chooses. DistanceRequest and DistanceBatch carry
// every field; MatrixRequest all but the deprecated exact_near_pairs.
struct DistanceChoice {
  int near_pairs = 0;  // a v1::NearPairs value, unchecked
  bool exact_near_pairs = false;
  double tolerance = 0;
  bool error_bounds = false;

  static DistanceChoice Of(const v1::DistanceRequest& request);
  static DistanceChoice Of(const v1::DistanceBatch& request);
  static DistanceChoice Of(const v1::MatrixRequest& request);
};

// The near-pair mode and tolerance of `choice`. The mode is the request's
// (near_pairs, or the deprecated exact_near_pairs), else the configuration's
// (exact_near_pairs, then unfold_near_pairs), else by path length; the
// tolerance is the request's when > 0, else the configuration's. Errors:
// InvalidArgument for an unknown near_pairs value, exact_near_pairs beside
// another mode, or a negative or non-finite tolerance.
absl::StatusOr<query::DistanceOptions> DistanceOptionsFor(const ModelConfig& config,
                                                          const DistanceChoice& choice);

// The exponential map's radius, reference direction and distance options
// (as DistanceOptionsFor). The centre is not read here (PointsFromProto).
// Errors: InvalidArgument for a reference direction that is not 3 numbers,
// and those of DistanceOptionsFor.
absl::StatusOr<query::ExpMapOptions> ExpMapOptionsFor(const ModelConfig& config,
                                                      const v1::ExpMapRequest& request);

// Most faces a Path call's exact corridor may reach round the trace: the
// exact solve costs a propagation over the corridor.
inline constexpr uint32_t kMaxPathCorridor = 64;

// The exact corridor of a Path call: the request's exact_corridor when > 0,
// else the configuration's exact_path_corridor clamped to [0,
// kMaxPathCorridor]. Errors: InvalidArgument for a request's corridor above
// kMaxPathCorridor.
absl::StatusOr<int32_t> PathCorridorFor(const ModelConfig& config, const v1::PathRequest& request);

}  // namespace geodex::server
