#pragma once

// The geodex.v1.Geodex service (proto/geodex/v1/geodex.proto) on gRPC's
// callback API. It holds no geometry: it resolves the model, converts and
// validates input (server/convert.h), runs the core engine on the worker pool
// and converts answers back. Errors leave through server/status_conversion.h.
//
// Threads. Reactions run on gRPC's threads and only move messages; every
// query, validation and conversion of a batch runs on the WorkerPool. A full
// pool queue answers RESOURCE_EXHAUSTED.
//
// Streams.
// - StreamDistances reads at most ServiceLimits::stream_window batches ahead
//   of the answers written, computes them on the pool (several at once with
//   several workers), and writes answers in batch order, one write in flight.
//   A slow reader therefore stops the reads, and HTTP/2 flow control pushes
//   back on the sender. A bad batch is answered with its error and the
//   stream goes on. Each batch resolves its model when it is computed, so a
//   long stream moves to a new version when one is swapped in (the answer
//   carries the version).
// - Matrix computes one block of rows, writes it, and computes the next only
//   when the write has completed; DistanceField computes the field, then
//   writes chunks of at most 1 MiB one at a time. GetMesh copies one chunk of
//   the mapped mesh on a worker, writes it, and copies the next only when the
//   write has completed; the resolved model (and so the mapped index) stays
//   alive until the stream ends, even if the version is swapped out meanwhile.
//
// Deadlines and cancellation: a call cancelled or past its deadline is not
// started, and long calls (Matrix rows, Path pairs, GetMesh chunks) stop
// between items.
//
// Shutdown: BeginShutdown makes new calls fail UNAVAILABLE and each running
// StreamDistances stop reading, answer the batches it has read,
// and finish UNAVAILABLE ("server shutting down", with the count of answered
// batches) so that the client can send the rest elsewhere. grpc::Server's
// Shutdown deadline bounds everything else.
//
// Thread safety: the service is shared by all gRPC threads; all members are
// thread-safe.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "server/auth.h"
#include "server/limits.h"
#include "server/metrics.h"
#include "server/model_registry.h"
#include "server/worker_pool.h"

namespace geodex::server {

class GeodexService final : public v1::Geodex::CallbackService {
 public:
  // The pointers must outlive the service (and so every call); `metrics` and
  // `auth` may be null (no metrics; no authentication).
  GeodexService(const ModelRegistry* registry, WorkerPool* pool, Metrics* metrics,
                const TokenAuth* auth, ServiceLimits limits);
  ~GeodexService() override;

  // See the header comment. Returns at once; idempotent.
  void BeginShutdown();
  // Streaming calls running now.
  int64_t active_streams() const;
  // True when no call of this service is running (unary or streaming).
  bool idle() const;

  grpc::ServerUnaryReactor* ListModels(grpc::CallbackServerContext* context,
                                       const v1::ListModelsRequest* request,
                                       v1::ListModelsResponse* response) override;
  grpc::ServerUnaryReactor* GetModel(grpc::CallbackServerContext* context,
                                     const v1::GetModelRequest* request,
                                     v1::ModelInfo* response) override;
  grpc::ServerUnaryReactor* Distance(grpc::CallbackServerContext* context,
                                     const v1::DistanceRequest* request,
                                     v1::DistanceResponse* response) override;
  grpc::ServerBidiReactor<v1::DistanceBatch, v1::DistanceResult>* StreamDistances(
      grpc::CallbackServerContext* context) override;
  grpc::ServerWriteReactor<v1::MatrixBlock>* Matrix(grpc::CallbackServerContext* context,
                                                    const v1::MatrixRequest* request) override;
  grpc::ServerUnaryReactor* Path(grpc::CallbackServerContext* context,
                                 const v1::PathRequest* request,
                                 v1::PathResponse* response) override;
  grpc::ServerWriteReactor<v1::DistanceFieldChunk>* DistanceField(
      grpc::CallbackServerContext* context, const v1::DistanceFieldRequest* request) override;
  grpc::ServerWriteReactor<v1::ExpMapChunk>* ExpMap(grpc::CallbackServerContext* context,
                                                    const v1::ExpMapRequest* request) override;
  grpc::ServerUnaryReactor* Locate(grpc::CallbackServerContext* context,
                                   const v1::LocateRequest* request,
                                   v1::LocateResponse* response) override;
  grpc::ServerWriteReactor<v1::MeshChunk>* GetMesh(grpc::CallbackServerContext* context,
                                                   const v1::GetMeshRequest* request) override;
  grpc::ServerUnaryReactor* GetTriangulation(grpc::CallbackServerContext* context,
                                             const v1::GetTriangulationRequest* request,
                                             v1::TriangulationResponse* response) override;

 private:
  // One call: what its log lines and metrics need.
  struct Call {
    const char* method = "";
    std::string request_id;
    std::string model;  // metrics label: a resolved model's name, else ""
    int64_t pairs = 0;  // work items answered
    std::chrono::steady_clock::time_point start;
  };
  class UnaryReactor;
  class StreamBase;
  template <class Reactor>
  class Stream;
  template <class Response>
  class ChunkedWriteStream;
  class DistanceStream;
  class MatrixStream;
  class FieldStream;
  class ExpMapStream;
  class MeshStream;

  // Names the call (the client's x-request-id if it sent a sane one) and
  // echoes the id in the initial metadata.
  Call StartCall(grpc::CallbackServerContext* context, const char* method) const;
  // Records metrics, logs an error once, and converts the status.
  grpc::Status FinishCall(Call& call, const absl::Status& status) const;
  absl::Status Authorize(const grpc::CallbackServerContext& context) const;
  // OK, or Cancelled / DeadlineExceeded once the call is over.
  static absl::Status CheckAlive(const grpc::CallbackServerContext& context);
  absl::Status Busy() const;
  absl::StatusOr<ResolvedModel> Resolve(const v1::ModelRef& ref, Call& call) const;
  ServiceLimits LimitsFor(const ModelSnapshot& model) const;
  // What a distance request chooses (DistanceRequest, DistanceBatch and
  // MatrixRequest carry the same fields).
  struct DistanceChoice {
    int near_pairs = 0;  // a v1::NearPairs value
    bool exact_near_pairs = false;
    double tolerance = 0;
    bool error_bounds = false;
    template <class Request>
    static DistanceChoice Of(const Request& r) {
      return {r.near_pairs(), r.exact_near_pairs(), r.tolerance(), r.error_bounds()};
    }
  };
  // a[i], b[i] -> out[i] (and bounds[i] when the request asks) with the
  // model's engine, near pairs and tolerance as the request or the model's
  // configuration says (validated, limited).
  absl::Status ComputeDistances(const ResolvedModel& model, const v1::SurfacePoints& a,
                                const v1::SurfacePoints& b, const DistanceChoice& choice,
                                WorkerContext& worker, google::protobuf::RepeatedField<double>* out,
                                google::protobuf::RepeatedField<double>* bounds) const;
  // Runs `fn(call, worker) -> absl::Status` on the pool and finishes the call
  // with its status.
  template <class Fn>
  grpc::ServerUnaryReactor* RunUnary(grpc::CallbackServerContext* context, const char* method,
                                     Fn fn);
  // Admits a streaming call. Errors: Unavailable while shutting down,
  // ResourceExhausted beyond max_concurrent_streams.
  absl::Status RegisterStream(StreamBase* stream);
  void UnregisterStream(StreamBase* stream);

  const ModelRegistry* const registry_;
  WorkerPool* const pool_;
  Metrics* const metrics_;
  const TokenAuth* const auth_;
  const ServiceLimits limits_;

  mutable std::mutex streams_mutex_;
  std::set<StreamBase*> streams_;  // registered, not owned (see StreamBase)
  std::atomic<bool> shutting_down_{false};
  std::atomic<int64_t> unary_in_flight_{0};
};

}  // namespace geodex::server
