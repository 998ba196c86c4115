#pragma once

// The service's server-streaming calls, from the proto's list of calls
// (geodex/v1/geodex_rpcs.h, generated from the service). GeodexService
// (server/geodex_service.h) declares and defines its method for
// every one, which only starts the call's reactor; so a new streamed call is
// its rpc in geodex.proto and its reactor (server/streams/<call>_stream.*),
// and neither this header nor the service's files change.
//
//   X(Name, Request, Chunk, Start)
//     Name     the rpc, as proto/geodex/v1/geodex.proto spells it
//     Request  its request message in geodex.v1
//     Chunk    the message it streams, in geodex.v1
//     Start    Start<Name>Stream: the function that admits and starts the
//              call's reactor, or returns one already finished with its
//              admission's error; declared below from this list, defined in
//              the reactor's file. `resources` and `request` must outlive
//              the call.
//
// StreamDistances, the one bidirectional stream, is declared by hand
// (distance_stream.h); the unary calls are the service's own methods.

#include "geodex/v1/geodex.pb.h"
#include "geodex/v1/geodex_rpcs.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/server_callback.h"

#define GEODEX_SERVER_STREAMED_CALLS(X) GEODEX_V1_RPCS(GEODEX_SERVER_STREAM_OF_KIND, X)
#define GEODEX_SERVER_STREAM_OF_KIND(Name, Request, Response, Kind, X) \
  GEODEX_SERVER_STREAM_##Kind(X, Name, Request, Response)
#define GEODEX_SERVER_STREAM_Unary(X, Name, Request, Response)
#define GEODEX_SERVER_STREAM_BidiStreaming(X, Name, Request, Response)
#define GEODEX_SERVER_STREAM_ServerStreaming(X, Name, Request, Chunk) \
  X(Name, Request, Chunk, Start##Name##Stream)

namespace geodex::server {

struct ServiceResources;

#define GEODEX_SERVER_DECLARE_START(Name, Request, Chunk, Start)                   \
  grpc::ServerWriteReactor<v1::Chunk>* Start(const ServiceResources* resources,    \
                                             grpc::CallbackServerContext* context, \
                                             const v1::Request* request);
GEODEX_SERVER_STREAMED_CALLS(GEODEX_SERVER_DECLARE_START)
#undef GEODEX_SERVER_DECLARE_START

}  // namespace geodex::server
