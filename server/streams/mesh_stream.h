#pragma once

// GetMesh: the input mesh (the mesh file's vertices and faces) in chunks of
// at most ServiceLimits::mesh_chunk_elements vertices and as many faces. It
// copies one chunk of the mapped index on the worker pool, writes it, and
// copies the next only when the write has completed; the resolved model
// (and so the mapped index) stays alive until the stream ends, even if the
// version is swapped out meanwhile.

#include "geodex/v1/geodex.pb.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/server_callback.h"

namespace geodex::server {

struct ServiceResources;

// The reactor of one GetMesh call, admitted or already finished with the
// error of its admission. `resources` and `request` must outlive the call.
grpc::ServerWriteReactor<v1::MeshChunk>* StartMeshStream(const ServiceResources* resources,
                                                         grpc::CallbackServerContext* context,
                                                         const v1::GetMeshRequest* request);

}  // namespace geodex::server
