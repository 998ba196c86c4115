#pragma once

// What a call of the Geodex service needs of the service that runs it, and
// nothing more: the models, the worker pool, the limits, metrics,
// authentication and the set of running streams. The unary calls
// (server/geodex_service.cc) and every stream reactor (server/streams/) see
// the service through this struct alone.
//
// Ownership: GeodexService owns one; every pointer it holds outlives the
// service, and so every call.
//
// Thread safety: immutable; the methods are safe from any thread.

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "geodex/v1/geodex.pb.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/status.h"
#include "server/config/limits.h"
#include "server/registry/model_registry.h"
#include "server/service/call.h"
#include "server/service/worker_pool.h"

namespace geodex::server {

class Metrics;
class StreamSet;
class TokenAuth;

struct ServiceResources {
  const ModelRegistry* registry = nullptr;
  WorkerPool* pool = nullptr;
  Metrics* metrics = nullptr;       // null: no metrics
  const TokenAuth* auth = nullptr;  // null: no authentication
  ServiceLimits limits;             // server-wide (see LimitsFor)
  StreamSet* streams = nullptr;     // the streaming calls running now

  // OK when the call may run. Errors: Unauthenticated (server/service/auth.h).
  absl::Status Authorize(const grpc::CallbackServerContext& context) const;
  // The model and version `ref` names, which becomes `call`'s metrics label.
  // Errors: those of ModelRegistry::Resolve.
  absl::StatusOr<ResolvedModel> Resolve(const v1::ModelRef& ref, Call& call) const;
  // The server's limits, lowered by `model`'s configuration.
  ServiceLimits LimitsFor(const ModelSnapshot& model) const;
  // The error of a job the full worker queue refused: ResourceExhausted.
  absl::Status Busy() const;
  // FinishCall with these metrics.
  grpc::Status Finish(const Call& call, const absl::Status& status) const;
};

}  // namespace geodex::server
