#pragma once

// The service's server-streaming calls, one line each. GeodexService
// (server/service/geodex_service.h) declares and defines its method for
// every line, which only starts the call's reactor; so a new streamed call is
// a line here and its reactor (server/streams/<call>_stream.*), and the
// service's files do not change.
//
//   X(Name, Request, Chunk, Start)
//     Name     the rpc, as proto/geodex/v1/geodex.proto spells it
//     Request  its request message in geodex.v1
//     Chunk    the message it streams, in geodex.v1
//     Start    the function that admits and starts the call's reactor, or
//              returns one already finished with its admission's error;
//              declared below from this list, defined in the reactor's file.
//              `resources` and `request` must outlive the call.
//
// StreamDistances, the one bidirectional stream, is declared by hand
// (distance_stream.h).

#include "geodex/v1/geodex.pb.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/server_callback.h"

#define GEODEX_SERVER_STREAMED_CALLS(X)                                        \
  X(Matrix, MatrixRequest, MatrixBlock, StartMatrixStream)                     \
  X(DistanceField, DistanceFieldRequest, DistanceFieldChunk, StartFieldStream) \
  X(ExpMap, ExpMapRequest, ExpMapChunk, StartExpMapStream)                     \
  X(GetMesh, GetMeshRequest, MeshChunk, StartMeshStream)

namespace geodex::server {

struct ServiceResources;

#define GEODEX_SERVER_DECLARE_START(Name, Request, Chunk, Start)                     \
  grpc::ServerWriteReactor<v1::Chunk>* Start(const ServiceResources* resources,     \
                                             grpc::CallbackServerContext* context, \
                                             const v1::Request* request);
GEODEX_SERVER_STREAMED_CALLS(GEODEX_SERVER_DECLARE_START)
#undef GEODEX_SERVER_DECLARE_START

}  // namespace geodex::server
