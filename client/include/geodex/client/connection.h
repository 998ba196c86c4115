#pragma once

// The connection interface under geodex::client::Client, in the style of
// google-cloud-cpp: Client does the work that is independent of the transport
// (batching, ordering, assembling streamed blocks, converting types); a
// GeodexConnection makes the calls. Connect() builds the gRPC one (with
// retries); tests and consumers that want no server use MockGeodexConnection
// (geodex/client/mocks/mock_geodex_connection.h) or their own subclass.
//
// Requests and responses are the geodex.v1 messages. Every method has a
// default implementation that returns UNIMPLEMENTED, so subclasses only
// override what they use and keep compiling when methods are added. The
// methods are listed once, in GEODEX_CLIENT_RPCS below.
//
// Thread safety: implementations must allow concurrent calls of every method
// from any number of threads. A DistanceStream is one call: one thread may
// Write while another Reads; other uses need the caller's synchronization.

#include <memory>
#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "geodex/v1/geodex.pb.h"
#include "geodex/v1/geodex_rpcs.h"

namespace geodex::client {

// One StreamDistances call. Results arrive in the order batches were written.
class DistanceStream {
 public:
  virtual ~DistanceStream() = default;

  // Sends a batch. False when the stream is broken; Finish says why.
  virtual bool Write(const v1::DistanceBatch& batch) = 0;
  // Tells the server no more batches come. False when the stream is broken.
  virtual bool WritesDone() = 0;
  // Blocks for the next result. False when there are no more: the server
  // finished, the stream broke or was cancelled; then call Finish.
  virtual bool Read(v1::DistanceResult* result) = 0;
  // Ends the call early; pending and later Read/Write calls fail soon.
  virtual void Cancel() = 0;
  // Blocks until the call ends and returns its status. Call once, after Read
  // returned false.
  virtual absl::Status Finish() = 0;
};

// Per-stream options of GeodexConnection::StreamDistances.
struct StreamOptions {
  // Deadline of the whole stream: unset, the connection's default
  // (ConnectOptions::deadline); absl::InfiniteDuration(), none.
  std::optional<absl::Duration> deadline;
};

// The calls of geodex.v1.Geodex other than StreamDistances:
// X(Name, Request, Result), where GeodexConnection::Name(request) returns
// absl::StatusOr<Result>. Result is the response of a unary call, or for a
// server-streaming call the std::vector of all its messages in the order
// received. The list is the proto's (geodex/v1/geodex_rpcs.h, generated from
// the service): the connection interface and its UNIMPLEMENTED defaults, the
// gRPC connection, the retrying connection and MockGeodexConnection are all
// expanded from it, so a new call is its rpc in geodex.proto (plus its typed
// method on Client). StreamDistances, the one bidirectional stream, is
// declared by hand below.
#define GEODEX_CLIENT_RPCS(X) GEODEX_V1_RPCS(GEODEX_CLIENT_RPC_OF_KIND, X)
#define GEODEX_CLIENT_RPC_OF_KIND(Name, Request, Response, Kind, X) \
  GEODEX_CLIENT_RPC_##Kind(X, Name, Request, Response)
#define GEODEX_CLIENT_RPC_Unary(X, Name, Request, Response) X(Name, v1::Request, v1::Response)
#define GEODEX_CLIENT_RPC_ServerStreaming(X, Name, Request, Chunk) \
  X(Name, v1::Request, std::vector<v1::Chunk>)
#define GEODEX_CLIENT_RPC_BidiStreaming(X, Name, Request, Response)

class GeodexConnection {
 public:
  virtual ~GeodexConnection() = default;

#define GEODEX_CLIENT_DECLARE_RPC(Name, Request, Result) \
  virtual absl::StatusOr<Result> Name(const Request& request);
  GEODEX_CLIENT_RPCS(GEODEX_CLIENT_DECLARE_RPC)
#undef GEODEX_CLIENT_DECLARE_RPC

  // Opens a stream. Never null; a stream that could not be opened fails its
  // first Write or Read and reports why in Finish.
  virtual std::unique_ptr<DistanceStream> StreamDistances(const StreamOptions& options);
};

}  // namespace geodex::client
