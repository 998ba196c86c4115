#pragma once

// ExpMap: the exponential map (geodesic polar coordinates) round one centre,
// every vertex within the request's radius. One job on the worker pool
// computes the whole map; its chunks of at most 1 MiB are then written one
// at a time, as DistanceField's. The request's options and the chunks are
// converted here, beside the reactor (the shared conversions are
// server/convert/convert.h).

#include <cstdint>
#include <span>

#include "absl/status/statusor.h"
#include "core/query/query_types.h"
#include "geodex/v1/geodex.pb.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/server_callback.h"
#include "server/config/model_config.h"

namespace geodex::server {

struct ServiceResources;

// The reactor of one ExpMap call, admitted or already finished with the
// error of its admission. `resources` and `request` must outlive the call.
grpc::ServerWriteReactor<v1::ExpMapChunk>* StartExpMapStream(const ServiceResources* resources,
                                                             grpc::CallbackServerContext* context,
                                                             const v1::ExpMapRequest* request);

// The exponential map's radius, reference direction and distance options
// (as DistanceOptionsFor). The centre is not read here (OnePointFromProto).
// Errors: InvalidArgument for a reference direction that is not 3 numbers,
// and those of DistanceOptionsFor. Thread safety: a pure function.
absl::StatusOr<query::ExpMapOptions> ExpMapOptionsFor(const ModelConfig& config,
                                                      const v1::ExpMapRequest& request);

// Entries [offset, offset + count) of an exponential map (in input ids:
// InputQueries::ExpMap) into `chunk`, which is cleared first.
void ExpMapChunkToProto(std::span<const query::ExpMapVertex> map, int64_t offset, int64_t count,
                        int64_t version, v1::ExpMapChunk* chunk);

}  // namespace geodex::server
