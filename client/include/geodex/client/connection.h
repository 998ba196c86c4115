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
// override what they use and keep compiling when methods are added.
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

class GeodexConnection {
 public:
  virtual ~GeodexConnection() = default;

  virtual absl::StatusOr<v1::ListModelsResponse> ListModels(const v1::ListModelsRequest& request);
  virtual absl::StatusOr<v1::ModelInfo> GetModel(const v1::GetModelRequest& request);
  virtual absl::StatusOr<v1::DistanceResponse> Distance(const v1::DistanceRequest& request);
  // Opens a stream. Never null; a stream that could not be opened fails its
  // first Write or Read and reports why in Finish.
  virtual std::unique_ptr<DistanceStream> StreamDistances(const StreamOptions& options);
  // All blocks of the server stream, in the order received.
  virtual absl::StatusOr<std::vector<v1::MatrixBlock>> Matrix(const v1::MatrixRequest& request);
  virtual absl::StatusOr<v1::PathResponse> Path(const v1::PathRequest& request);
  // All chunks of the server stream, in the order received.
  virtual absl::StatusOr<std::vector<v1::DistanceFieldChunk>> DistanceField(
      const v1::DistanceFieldRequest& request);
  virtual absl::StatusOr<v1::LocateResponse> Locate(const v1::LocateRequest& request);
  // All chunks of the server stream, in the order received.
  virtual absl::StatusOr<std::vector<v1::MeshChunk>> GetMesh(const v1::GetMeshRequest& request);
  // All chunks of the server stream, in the order received.
  virtual absl::StatusOr<std::vector<v1::ExpMapChunk>> ExpMap(const v1::ExpMapRequest& request);
  virtual absl::StatusOr<v1::TriangulationResponse> GetTriangulation(
      const v1::GetTriangulationRequest& request);
};

}  // namespace geodex::client
