#pragma once

// The distances of one Distance call or one StreamDistances batch: limits,
// options, points and the engine, in that order (the first error wins).
//
// Thread safety: as the model's queries (const); `worker` is the caller's.

#include "absl/status/status.h"
#include "geodex/v1/geodex.pb.h"
#include "server/config/limits.h"
#include "server/convert/convert.h"
#include "server/registry/model_registry.h"
#include "server/service/worker_pool.h"

namespace geodex::server {

// out[i] = d(a[i], b[i]) (and bounds[i] when `choice` asks for bounds) with
// `model`'s queries and the options `choice` and the model's configuration
// give (DistanceOptionsFor). `limits` are the model's (ServiceLimits after
// WithModelLimits). Errors: ResourceExhausted beyond max_pairs_per_message;
// InvalidArgument when a and b do not pair up; those of DistanceOptionsFor,
// PointsFromProto and InputQueries::DistanceBatch.
absl::Status ComputeDistances(const ResolvedModel& model, const ServiceLimits& limits,
                              const v1::SurfacePoints& a, const v1::SurfacePoints& b,
                              const DistanceChoice& choice, WorkerContext& worker,
                              google::protobuf::RepeatedField<double>* out,
                              google::protobuf::RepeatedField<double>* bounds);

}  // namespace geodex::server
