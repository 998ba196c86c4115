#pragma once

// ExpMap: the exponential map (geodesic polar coordinates) round one centre,
// every vertex within the request's radius. One job on the worker pool
// computes the whole map; its chunks of at most 1 MiB are then written one
// at a time, as DistanceField's.

#include "geodex/v1/geodex.pb.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/server_callback.h"

namespace geodex::server {

struct ServiceResources;

// The reactor of one ExpMap call, admitted or already finished with the
// error of its admission. `resources` and `request` must outlive the call.
grpc::ServerWriteReactor<v1::ExpMapChunk>* StartExpMapStream(const ServiceResources* resources,
                                                             grpc::CallbackServerContext* context,
                                                             const v1::ExpMapRequest* request);

}  // namespace geodex::server
