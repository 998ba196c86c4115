#pragma once

// The geodex.v1.Geodex service (proto/geodex/v1/geodex.proto) on gRPC's
// callback API. It holds no geometry: it resolves the model, converts and
// validates input (server/convert/), checks the limits
// (server/config/limits.h), runs the core engine on the worker pool and
// converts answers back. Errors leave through status_conversion.h.
//
// Threads. Reactions run on gRPC's threads and only move messages; every
// query, validation and conversion of a batch runs on the WorkerPool. A full
// pool queue answers RESOURCE_EXHAUSTED.
//
// Streams. Each streaming call has a reactor of its own in server/streams/
// (<call>_stream.cc; the server-streaming ones are listed, and their start
// functions declared, in streamed_calls.h; StreamDistances' in
// distance_stream.h), which sees
// the service only through ServiceResources (service_resources.h). They
// write one message at a time and make the next when the write has
// completed (backpressure).
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
#include <cstdint>

#include "geodex/v1/geodex.grpc.pb.h"
#include "server/config/limits.h"
#include "server/registry/model_registry.h"
#include "server/service/auth.h"
#include "server/service/metrics.h"
#include "server/service/service_resources.h"
#include "server/service/worker_pool.h"
#include "server/streams/stream_set.h"
#include "server/streams/streamed_calls.h"

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
  grpc::ServerUnaryReactor* Path(grpc::CallbackServerContext* context,
                                 const v1::PathRequest* request,
                                 v1::PathResponse* response) override;
  grpc::ServerUnaryReactor* Locate(grpc::CallbackServerContext* context,
                                   const v1::LocateRequest* request,
                                   v1::LocateResponse* response) override;
  grpc::ServerUnaryReactor* GetTriangulation(grpc::CallbackServerContext* context,
                                             const v1::GetTriangulationRequest* request,
                                             v1::TriangulationResponse* response) override;

  // The server-streaming calls (server/streams/streamed_calls.h), each of
  // which starts its reactor.
#define GEODEX_SERVER_DECLARE_STREAM(Name, Request, Chunk, Start)                 \
  grpc::ServerWriteReactor<v1::Chunk>* Name(grpc::CallbackServerContext* context, \
                                            const v1::Request* request) override;
  GEODEX_SERVER_STREAMED_CALLS(GEODEX_SERVER_DECLARE_STREAM)
#undef GEODEX_SERVER_DECLARE_STREAM

 private:
  // Runs `fn(call, worker) -> absl::Status` on the pool and finishes the call
  // with its status.
  template <class Fn>
  grpc::ServerUnaryReactor* RunUnary(grpc::CallbackServerContext* context, const char* method,
                                     Fn fn);

  StreamSet streams_;
  const ServiceResources resources_;  // points at streams_
  std::atomic<int64_t> unary_in_flight_{0};
};

}  // namespace geodex::server
