#pragma once

// geodex::client::Client: geodesic distances, paths and distance fields from a
// geodex server (proto/geodex/v1/geodex.proto).
//
//   absl::StatusOr<geodex::Client> client = geodex::client::Connect("localhost:50051");
//   if (!client.ok()) return client.status();
//   std::vector<geodex::client::PointPair> pairs = ...;
//   absl::StatusOr<std::vector<double>> d = client->Distance("torus", pairs);
//
// Errors are absl::Status values with the server's code and message:
// NOT_FOUND for an unknown model or version, UNAVAILABLE while a model is
// loading (retried, see RetryPolicy) or when the server cannot be reached,
// INVALID_ARGUMENT for malformed input (the message names the element),
// OUT_OF_RANGE for a face id past the end, RESOURCE_EXHAUSTED beyond a server
// limit, DEADLINE_EXCEEDED when ConnectOptions::deadline passed.
//
// Thread safety: a Client is a cheap value (a shared connection and a few
// options); copies share the connection. Every const method may be called
// concurrently from any number of threads on the same or on copied Clients.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "geodex/client/connection.h"
#include "geodex/client/options.h"
#include "geodex/client/types.h"

namespace geodex::client {

// One batch's answer in a DistanceSession.
struct DistanceBatchResult {
  uint64_t batch_id = 0;  // as returned by DistanceSession::Send
  // OK, or why the server rejected this batch (the session goes on).
  absl::Status status;
  std::vector<double> distances;  // distances[i] = d(pairs[i].a, pairs[i].b)
  int64_t version = 0;            // the model version that answered
};

// A StreamDistances call for callers that produce pairs continuously: Send
// batches as they come, Read the answers (in the order sent) as they arrive.
//
//   auto session = client.OpenDistanceSession("torus");
//   std::thread reader([&] {
//     while (auto r = session.Read()) Consume(*r);
//   });
//   for (...) if (!session.Send(batch).ok()) break;
//   session.CloseSend();
//   reader.join();
//   absl::Status status = session.Finish();
//
// A session is not retried: when the stream breaks, Send fails and Read
// returns nullopt, and Finish reports why. (Client::Distance does resume a
// broken stream.)
//
// Thread safety: Send/CloseSend may be called from several threads (they are
// serialized) concurrently with Read from another thread; Read calls are
// serialized too. Finish must not run concurrently with the others.
class DistanceSession {
 public:
  DistanceSession(DistanceSession&&) noexcept;
  DistanceSession& operator=(DistanceSession&&) noexcept;
  // Cancels the stream if Finish was not called.
  ~DistanceSession();

  // Sends one batch (any size > 0; the server may limit it) and returns its id
  // (0, 1, 2, ... in sending order). Errors: FAILED_PRECONDITION after
  // CloseSend; UNAVAILABLE (or the stream's own error, if known) when the
  // stream is broken.
  absl::StatusOr<uint64_t> Send(absl::Span<const PointPair> pairs);
  // No more batches. Idempotent.
  void CloseSend();
  // The next batch's answer, in sending order; nullopt when the stream ended
  // (after CloseSend and all answers, or because it broke).
  std::optional<DistanceBatchResult> Read();
  // Cancels the stream; pending Send/Read fail soon.
  void Cancel();
  // The stream's final status. Call once, after Read returned nullopt (or
  // after Cancel).
  absl::Status Finish();

 private:
  friend class Client;
  struct State;
  explicit DistanceSession(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

class Client {
 public:
  // A client over any connection, e.g. a MockGeodexConnection in tests.
  explicit Client(std::shared_ptr<GeodexConnection> connection, ClientOptions options = {});

  // Every model the server knows, in the server's order.
  absl::StatusOr<std::vector<ModelInfo>> ListModels() const;
  // One model. Errors: NOT_FOUND.
  absl::StatusOr<ModelInfo> GetModel(const ModelRef& model) const;

  // d(pairs[i].a, pairs[i].b) for every i, in input order; any number of
  // pairs. Up to ClientOptions::batch_size pairs go in one Distance call;
  // more are split into batches pipelined over one StreamDistances stream
  // (a writer thread sends while the calling thread reads). A stream broken by
  // a retryable error is reopened and the unanswered batches re-sent. A batch
  // rejected by the server fails the whole call; the message says which pairs
  // ("pairs [8192, 12288): ..."). +Infinity: unreachable.
  //
  // All batches name `model` as given: with version 0, a call that overlaps a
  // model reload may be answered partly by the old and partly by the new
  // version. Pin ModelRef::version to avoid that.
  //
  // Each attempt (the unary call, or one stream) must end within
  // ConnectOptions::deadline; raise it for very large inputs.
  absl::StatusOr<std::vector<double>> Distance(
      const ModelRef& model, absl::Span<const PointPair> pairs,
      NearPairs near_pairs = NearPairs::kModelDefault) const;
  // The same with a tolerance and error bounds (DistanceQuery). Errors as
  // above; FAILED_PRECONDITION when a bound or tolerance is asked of a model
  // whose index has no accuracy calibration, INVALID_ARGUMENT for a negative
  // tolerance.
  absl::StatusOr<Distances> Distance(const ModelRef& model, absl::Span<const PointPair> pairs,
                                     const DistanceQuery& query) const;

  // Opens a streaming session (see DistanceSession).
  DistanceSession OpenDistanceSession(const ModelRef& model, SessionOptions options = {}) const;

  // The sources x targets matrix, assembled from the streamed row blocks.
  // Errors: DATA_LOSS if the blocks do not tile the matrix.
  absl::StatusOr<DistanceMatrix> Matrix(const ModelRef& model,
                                        absl::Span<const SurfacePoint> sources,
                                        absl::Span<const SurfacePoint> targets,
                                        NearPairs near_pairs = NearPairs::kModelDefault) const;

  // Geodesic paths for point pairs, in input order (ClientOptions::
  // path_batch_size pairs per call). exact_corridor > 0 (at most 64) asks the
  // server to also solve each path exactly within that many edge steps of
  // the traced one (geodex.v1.PathRequest.exact_corridor); 0: the model's
  // default.
  absl::StatusOr<std::vector<GeodesicPath>> Path(const ModelRef& model,
                                                 absl::Span<const PointPair> pairs,
                                                 uint32_t exact_corridor = 0) const;

  // Distance from the nearest source to every mesh vertex, assembled from the
  // streamed chunks. Errors: DATA_LOSS if the chunks do not cover every
  // vertex exactly once.
  absl::StatusOr<VertexDistances> DistanceField(const ModelRef& model,
                                                absl::Span<const SurfacePoint> sources,
                                                bool with_nearest_source = false) const;

  // The exact distance from the nearest source to every mesh vertex within
  // query.radius, and only those (geodex.v1.DistanceFieldRequest.radius):
  // one exact propagation on the server whose cost follows the vertices it
  // reaches, for many targets round few sources (local descriptors,
  // learning on meshes). Entries ascend by vertex. Errors: INVALID_ARGUMENT
  // for a radius that is not finite and > 0 (checked here) or bad sources;
  // RESOURCE_EXHAUSTED past the server's max_field_vertices; DATA_LOSS if
  // the chunks are not one consistent answer, or the server answered with
  // a whole-mesh field (one older than radius fields).
  absl::StatusOr<VertexDistancesWithin> DistanceFieldWithin(const ModelRef& model,
                                                            absl::Span<const SurfacePoint> sources,
                                                            const FieldWithinQuery& query) const;

  // The exponential map round `center` (geodesic polar coordinates of every
  // vertex within query.radius), assembled from the streamed chunks; entries
  // ascend by vertex. Errors: INVALID_ARGUMENT for a bad centre, radius or
  // reference direction (checked here where possible); DATA_LOSS if the
  // chunks are not one consistent map.
  absl::StatusOr<client::ExpMap> ExpMap(const ModelRef& model, const SurfacePoint& center,
                                        const ExpMapQuery& query) const;

  // The closest surface point of each position, in input order.
  absl::StatusOr<std::vector<LocatedPoint>> Locate(const ModelRef& model,
                                                   absl::Span<const Position> positions) const;

  // The model's triangle mesh, assembled from the streamed chunks; Mesh::version
  // says which version it is. To get the mesh a DistanceField was computed on,
  // pin the field's version:
  //
  //   absl::StatusOr<VertexDistances> field = client.DistanceField("torus", sources);
  //   absl::StatusOr<Mesh> mesh = client.GetMesh({"torus", field->version});
  //
  // Errors: NOT_FOUND for an unknown model or version (also when a pinned
  // version has been retired meanwhile); DATA_LOSS if the chunks are not one
  // consistent mesh (totals or version that change between chunks, vertex or
  // face ranges that are not contiguous or do not add up to the totals, a face
  // naming a vertex past the end, the mesh of another version than the pinned
  // one).
  absl::StatusOr<Mesh> GetMesh(const ModelRef& model) const;

  const std::shared_ptr<GeodexConnection>& connection() const { return connection_; }
  const ClientOptions& options() const { return options_; }

 private:
  std::shared_ptr<GeodexConnection> connection_;
  ClientOptions options_;
};

// A gRPC connection to `target` with retries (ConnectOptions::retry) around
// every call except StreamDistances.
//
// `target` is any gRPC target: "host:port", "dns:///name:port" (all addresses
// the name resolves to), "ipv4:10.0.0.1:50051,10.0.0.2:50051", "unix:/path".
// A plain comma-separated list of IP literals with ports ("10.0.0.1:50051,
// 10.0.0.2:50051", "[::1]:1,[::1]:2") becomes the ipv4:/ipv6: form. Calls are
// spread over the addresses by ConnectOptions::load_balancing_policy.
//
// Does not wait for the server: the first call connects. Errors:
// INVALID_ARGUMENT for an empty or malformed target, inconsistent TLS options
// or a token with characters not allowed in a header; NOT_FOUND when a TLS
// file cannot be read.
absl::StatusOr<std::shared_ptr<GeodexConnection>> MakeGrpcConnection(
    const std::string& target, const ConnectOptions& options = {});

// A Client over MakeGrpcConnection(target, options).
absl::StatusOr<Client> Connect(const std::string& target, const ConnectOptions& options = {});

}  // namespace geodex::client

namespace geodex {
// geodex::Client, the name most callers want; the library lives in geodex::client.
using Client = client::Client;
}  // namespace geodex
