#pragma once

// DistanceField: the distance of every vertex of the input mesh from its
// nearest source, or, with a radius, the exact distances of the vertices
// within it (sparse chunks: vertices with their distances). One job on the
// worker pool computes the whole field; its chunks of at most 1 MiB are then
// written one at a time.

#include "geodex/v1/geodex.pb.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/server_callback.h"

namespace geodex::server {

struct ServiceResources;

// The reactor of one DistanceField call, admitted or already finished with
// the error of its admission. `resources` and `request` must outlive the
// call.
grpc::ServerWriteReactor<v1::DistanceFieldChunk>* StartFieldStream(
    const ServiceResources* resources, grpc::CallbackServerContext* context,
    const v1::DistanceFieldRequest* request);

}  // namespace geodex::server
