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
//     Start    the function that admits and starts the call's reactor:
//              grpc::ServerWriteReactor<v1::Chunk>* Start(
//                  const ServiceResources*, grpc::CallbackServerContext*,
//                  const v1::Request*)
//
// StreamDistances, the one bidirectional stream, is declared by hand.

#include "server/streams/exp_map_stream.h"
#include "server/streams/field_stream.h"
#include "server/streams/matrix_stream.h"
#include "server/streams/mesh_stream.h"

#define GEODEX_SERVER_STREAMED_CALLS(X)                                        \
  X(Matrix, MatrixRequest, MatrixBlock, StartMatrixStream)                     \
  X(DistanceField, DistanceFieldRequest, DistanceFieldChunk, StartFieldStream) \
  X(ExpMap, ExpMapRequest, ExpMapChunk, StartExpMapStream)                     \
  X(GetMesh, GetMeshRequest, MeshChunk, StartMeshStream)
