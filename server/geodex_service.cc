// GeodexService: admission, the calls' bookkeeping, the unary calls, and the
// registration of streaming calls. The streams themselves are in
// geodex_service_distance_stream.cc and geodex_service_write_streams.cc.

#include "server/geodex_service.h"

#include <algorithm>
#include <atomic>
#include <random>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "server/convert.h"
#include "server/geodex_service_stream.h"
#include "server/model_config.h"
#include "server/status_conversion.h"
#include "spdlog/spdlog.h"

namespace geodex::server {
namespace service_internal {

namespace {

absl::StatusOr<query::NearPairs> NearPairsFor(const ModelSnapshot& model, int requested,
                                              bool exact_requested) {
  if (!v1::NearPairs_IsValid(requested)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("near_pairs has the unknown value %d", requested));
  }
  if (exact_requested && requested != v1::NEAR_PAIRS_UNSPECIFIED &&
      requested != v1::NEAR_PAIRS_EXACT) {
    return absl::InvalidArgumentError(
        absl::StrFormat("exact_near_pairs contradicts near_pairs = %s",
                        v1::NearPairs_Name(static_cast<v1::NearPairs>(requested))));
  }
  if (exact_requested) return query::NearPairs::kExact;
  switch (static_cast<v1::NearPairs>(requested)) {
    case v1::NEAR_PAIRS_PATH:
      return query::NearPairs::kPath;
    case v1::NEAR_PAIRS_UNFOLD:
      return query::NearPairs::kUnfold;
    case v1::NEAR_PAIRS_EXACT:
      return query::NearPairs::kExact;
    default:
      break;
  }
  if (model.config.exact_near_pairs()) return query::NearPairs::kExact;
  if (model.config.unfold_near_pairs()) return query::NearPairs::kUnfold;
  return query::NearPairs::kPath;
}

}  // namespace

absl::StatusOr<query::DistanceOptions> DistanceOptionsFor(const ModelSnapshot& model,
                                                          int near_pairs, bool exact_near_pairs,
                                                          double tolerance) {
  query::DistanceOptions options;
  GEODEX_ASSIGN_OR_RETURN(options.near_pairs,
                          NearPairsFor(model, near_pairs, exact_near_pairs));
  if (!(tolerance >= 0) || !std::isfinite(tolerance)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tolerance must be finite and >= 0, not %g", tolerance));
  }
  options.tolerance = tolerance > 0 ? tolerance : model.config.tolerance();
  return options;
}

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

bool IsClientError(absl::StatusCode code) {
  switch (code) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kOutOfRange:
    case absl::StatusCode::kNotFound:
    case absl::StatusCode::kResourceExhausted:
    case absl::StatusCode::kUnauthenticated:
    case absl::StatusCode::kCancelled:
    case absl::StatusCode::kDeadlineExceeded:
      return true;
    default:
      return false;
  }
}

}  // namespace service_internal

namespace {

using service_internal::Clock;
using service_internal::IsClientError;
using service_internal::DistanceOptionsFor;
using service_internal::SecondsSince;

// A client-supplied request id is used when it is short and printable.
bool IsSaneRequestId(grpc::string_ref id) {
  if (id.empty() || id.size() > 64) return false;
  return std::all_of(id.begin(), id.end(), [](char c) { return c > ' ' && c < 127; });
}

std::string NewRequestId() {
  static const uint32_t prefix = std::random_device()();
  static std::atomic<uint64_t> counter{0};
  return absl::StrFormat("%08x-%d", prefix, counter.fetch_add(1) + 1);
}

absl::Status WithPrefix(const absl::Status& status, const std::string& prefix) {
  return absl::Status(status.code(), prefix + std::string(status.message()));
}

}  // namespace

// --- calls ------------------------------------------------------------------------

GeodexService::GeodexService(const ModelRegistry* registry, WorkerPool* pool, Metrics* metrics,
                             const TokenAuth* auth, ServiceLimits limits)
    : registry_(registry), pool_(pool), metrics_(metrics), auth_(auth), limits_(limits) {}

GeodexService::~GeodexService() = default;

GeodexService::Call GeodexService::StartCall(grpc::CallbackServerContext* context,
                                             const char* method) const {
  Call call;
  call.method = method;
  call.start = Clock::now();
  const auto& metadata = context->client_metadata();
  auto it = metadata.find("x-request-id");
  call.request_id = it != metadata.end() && IsSaneRequestId(it->second)
                        ? std::string(it->second.data(), it->second.size())
                        : NewRequestId();
  context->AddInitialMetadata("x-request-id", call.request_id);
  return call;
}

grpc::Status GeodexService::FinishCall(Call& call, const absl::Status& status) const {
  const double seconds = SecondsSince(call.start);
  if (metrics_ != nullptr) {
    metrics_->RecordCall(call.method, call.model, status.code(), call.pairs, seconds);
  }
  if (!status.ok()) {
    const auto level = IsClientError(status.code()) ? spdlog::level::info : spdlog::level::warn;
    spdlog::log(level, "[{}] {} model='{}' failed after {:.6f}s: {}", call.request_id, call.method,
                call.model, seconds, status.ToString());
  } else {
    spdlog::debug("[{}] {} model='{}' ok: {} items in {:.6f}s", call.request_id, call.method,
                  call.model, call.pairs, seconds);
  }
  return ToGrpcStatus(status);
}

absl::Status GeodexService::Authorize(const grpc::CallbackServerContext& context) const {
  return auth_ == nullptr ? absl::OkStatus() : auth_->Check(context);
}

absl::Status GeodexService::CheckAlive(const grpc::CallbackServerContext& context) {
  if (!context.IsCancelled()) return absl::OkStatus();
  if (context.deadline() <= std::chrono::system_clock::now()) {
    return absl::DeadlineExceededError("deadline exceeded");
  }
  return absl::CancelledError("call cancelled");
}

absl::Status GeodexService::Busy() const {
  return absl::ResourceExhaustedError(
      absl::StrFormat("server busy: %d jobs queued for %d workers; retry later",
                      pool_->queue_depth(), pool_->threads()));
}

absl::StatusOr<ResolvedModel> GeodexService::Resolve(const v1::ModelRef& ref, Call& call) const {
  absl::StatusOr<ResolvedModel> resolved = registry_->Resolve(ref.name(), ref.version());
  if (resolved.ok()) call.model = resolved->model->name;
  return resolved;
}

ServiceLimits GeodexService::LimitsFor(const ModelSnapshot& model) const {
  return WithModelLimits(limits_, model.config.limits());
}

absl::Status GeodexService::ComputeDistances(const ResolvedModel& model, const v1::SurfacePoints& a,
                                             const v1::SurfacePoints& b,
                                             const DistanceChoice& choice, WorkerContext& worker,
                                             google::protobuf::RepeatedField<double>* out,
                                             google::protobuf::RepeatedField<double>* bounds) const {
  const ServiceLimits limits = LimitsFor(*model.model);
  const int64_t na = PointCount(a), nb = PointCount(b);
  if (std::max(na, nb) > limits.max_pairs_per_message) {
    return absl::ResourceExhaustedError(
        absl::StrFormat("%d pairs exceed the limit of %d per message (max_pairs_per_message)",
                        std::max(na, nb), limits.max_pairs_per_message));
  }
  if (na != nb) {
    return absl::InvalidArgumentError(
        absl::StrFormat("a has %d points but b has %d; they must pair up", na, nb));
  }
  GEODEX_ASSIGN_OR_RETURN(const query::DistanceOptions options,
                          DistanceOptionsFor(*model.model, choice.near_pairs,
                                             choice.exact_near_pairs, choice.tolerance));
  const query::InputQueries& queries = model.version->queries();
  GEODEX_RETURN_IF_ERROR(PointsFromProto(a, "a", queries, &worker.a));
  GEODEX_RETURN_IF_ERROR(PointsFromProto(b, "b", queries, &worker.b));
  return queries.DistanceBatch(worker.a, worker.b, ResizeForOutput(out, na), options,
                               &worker.scratch,
                               choice.error_bounds ? ResizeForOutput(bounds, na)
                                                   : std::span<double>());
}

// A unary call's reactor. It counts the call from its start until gRPC is
// done with it (OnDone: the status has been sent or the call has failed), so
// that shutdown knows when every call has really ended. Ownership: gRPC's
// from the handler's return to OnDone, where it deletes itself.
class GeodexService::UnaryReactor final : public grpc::ServerUnaryReactor {
 public:
  explicit UnaryReactor(GeodexService* service) : service_(service) {
    ++service_->unary_in_flight_;
  }
  void OnDone() override {
    --service_->unary_in_flight_;
    delete this;
  }

 private:
  GeodexService* const service_;
};

template <class Fn>
grpc::ServerUnaryReactor* GeodexService::RunUnary(grpc::CallbackServerContext* context,
                                                  const char* method, Fn fn) {
  auto* reactor = new UnaryReactor(this);
  auto call = std::make_shared<Call>(StartCall(context, method));
  absl::Status status = Authorize(*context);
  if (status.ok() && shutting_down_) status = absl::UnavailableError("server is shutting down");
  if (!status.ok()) {
    reactor->Finish(FinishCall(*call, status));
    return reactor;
  }
  // The request, response and context live until Finish; the job calls
  // Finish exactly once.
  const bool queued = pool_->Submit([this, context, reactor, call, fn](WorkerContext& worker) {
    absl::Status status = CheckAlive(*context);
    if (status.ok()) status = fn(*call, worker);
    reactor->Finish(FinishCall(*call, status));
  });
  if (!queued) reactor->Finish(FinishCall(*call, Busy()));
  return reactor;
}

// --- unary calls ------------------------------------------------------------------

grpc::ServerUnaryReactor* GeodexService::ListModels(grpc::CallbackServerContext* context,
                                                    const v1::ListModelsRequest* /*request*/,
                                                    v1::ListModelsResponse* response) {
  return RunUnary(context, "ListModels", [this, response](Call&, WorkerContext&) {
    std::shared_ptr<const RegistrySnapshot> snapshot = registry_->snapshot();
    for (const auto& [name, model] : snapshot->models) {
      ModelInfoToProto(*model, model->newest(), response->add_models());
    }
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* GeodexService::GetModel(grpc::CallbackServerContext* context,
                                                  const v1::GetModelRequest* request,
                                                  v1::ModelInfo* response) {
  return RunUnary(context, "GetModel", [this, request, response](Call& call, WorkerContext&) {
    const v1::ModelRef& ref = request->model();
    GEODEX_RETURN_IF_ERROR(ValidateModelName(ref.name()));
    if (ref.version() < 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("model version %d is negative", ref.version()));
    }
    std::shared_ptr<const RegistrySnapshot> snapshot = registry_->snapshot();
    auto it = snapshot->models.find(ref.name());
    if (it == snapshot->models.end()) {
      if (!snapshot->initial_scan_done) {
        return absl::UnavailableError("the model repository is still being scanned");
      }
      return absl::NotFoundError(absl::StrFormat("unknown model '%s'", ref.name()));
    }
    const ModelSnapshot& model = *it->second;
    call.model = model.name;
    if (ref.version() == 0) {
      ModelInfoToProto(model, model.newest(), response);
      return absl::OkStatus();
    }
    // A pinned version: described if served.
    GEODEX_ASSIGN_OR_RETURN(ResolvedModel resolved, Resolve(ref, call));
    ModelInfoToProto(model, resolved.version, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* GeodexService::Distance(grpc::CallbackServerContext* context,
                                                  const v1::DistanceRequest* request,
                                                  v1::DistanceResponse* response) {
  return RunUnary(context, "Distance",
                  [this, request, response](Call& call, WorkerContext& worker) -> absl::Status {
                    GEODEX_ASSIGN_OR_RETURN(ResolvedModel model, Resolve(request->model(), call));
                    GEODEX_RETURN_IF_ERROR(ComputeDistances(
                        model, request->a(), request->b(), DistanceChoice::Of(*request), worker,
                        response->mutable_distances(), response->mutable_bounds()));
                    call.pairs = PointCount(request->a());
                    response->set_version(model.version->version());
                    return absl::OkStatus();
                  });
}

grpc::ServerUnaryReactor* GeodexService::Path(grpc::CallbackServerContext* context,
                                              const v1::PathRequest* request,
                                              v1::PathResponse* response) {
  return RunUnary(
      context, "Path",
      [this, context, request, response](Call& call, WorkerContext& worker) -> absl::Status {
        GEODEX_ASSIGN_OR_RETURN(ResolvedModel model, Resolve(request->model(), call));
        const ServiceLimits limits = LimitsFor(*model.model);
        const int64_t na = PointCount(request->a()), nb = PointCount(request->b());
        if (std::max(na, nb) > limits.max_path_pairs) {
          return absl::ResourceExhaustedError(
              absl::StrFormat("%d pairs exceed the limit of %d per Path call (max_path_pairs)",
                              std::max(na, nb), limits.max_path_pairs));
        }
        if (na != nb) {
          return absl::InvalidArgumentError(
              absl::StrFormat("a has %d points but b has %d; they must pair up", na, nb));
        }
        constexpr uint32_t kMaxCorridor = 64;
        if (request->exact_corridor() > kMaxCorridor) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "exact_corridor %d exceeds %d", request->exact_corridor(), kMaxCorridor));
        }
        const int32_t corridor =
            request->exact_corridor() > 0
                ? static_cast<int32_t>(request->exact_corridor())
                : std::clamp<int32_t>(model.model->config.exact_path_corridor(), 0, kMaxCorridor);
        const query::InputQueries& queries = model.version->queries();
        GEODEX_RETURN_IF_ERROR(PointsFromProto(request->a(), "a", queries, &worker.a));
        GEODEX_RETURN_IF_ERROR(PointsFromProto(request->b(), "b", queries, &worker.b));
        response->mutable_paths()->Reserve(static_cast<int>(na));
        for (int64_t i = 0; i < na; ++i) {
          GEODEX_RETURN_IF_ERROR(CheckAlive(*context));
          absl::StatusOr<std::vector<query::PathPoint>> path =
              queries.Path(worker.a, i, worker.b, i, corridor);
          if (path.ok()) {
            PathToProto(*path, response->add_paths());
          } else if (path.status().code() == absl::StatusCode::kNotFound) {
            UnreachablePathToProto(response->add_paths());  // different components
          } else {
            return WithPrefix(path.status(), absl::StrFormat("pair %d: ", i));
          }
        }
        call.pairs = na;
        response->set_version(model.version->version());
        return absl::OkStatus();
      });
}

grpc::ServerUnaryReactor* GeodexService::Locate(grpc::CallbackServerContext* context,
                                                const v1::LocateRequest* request,
                                                v1::LocateResponse* response) {
  return RunUnary(
      context, "Locate", [this, request, response](Call& call, WorkerContext&) -> absl::Status {
        GEODEX_ASSIGN_OR_RETURN(ResolvedModel model, Resolve(request->model(), call));
        const ServiceLimits limits = LimitsFor(*model.model);
        const int64_t n = request->positions().xyz_size() / 3;
        if (n > limits.max_locate_positions) {
          return absl::ResourceExhaustedError(
              absl::StrFormat("%d positions exceed the limit of %d per Locate call "
                              "(max_locate_positions)",
                              n, limits.max_locate_positions));
        }
        std::vector<mesh::Vec3> positions;
        GEODEX_RETURN_IF_ERROR(PositionsFromProto(request->positions(), "positions", &positions));
        const query::InputQueries& queries = model.version->queries();
        for (size_t i = 0; i < positions.size(); ++i) {
          absl::StatusOr<query::LocatedPoint> located = queries.Locate(positions[i]);
          if (!located.ok()) {
            return WithPrefix(located.status(), absl::StrFormat("positions[%d]: ", i));
          }
          AppendLocated(*located, response);
        }
        call.pairs = n;
        response->set_version(model.version->version());
        return absl::OkStatus();
      });
}

grpc::ServerUnaryReactor* GeodexService::GetTriangulation(
    grpc::CallbackServerContext* context, const v1::GetTriangulationRequest* request,
    v1::TriangulationResponse* response) {
  return RunUnary(context, "GetTriangulation",
                  [this, request, response](Call& call, WorkerContext&) -> absl::Status {
                    GEODEX_ASSIGN_OR_RETURN(ResolvedModel model, Resolve(request->model(), call));
                    TriangulationToProto(model.version->queries(), model.version->version(),
                                         response);
                    call.pairs = model.version->queries().num_vertices();
                    return absl::OkStatus();
                  });
}

// --- streaming calls: registration and shutdown ---------------------------------

absl::Status GeodexService::RegisterStream(StreamBase* stream) {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  if (shutting_down_) return absl::UnavailableError("server is shutting down");
  if (static_cast<int64_t>(streams_.size()) >= limits_.max_concurrent_streams) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "%d streaming calls already running (max_concurrent_streams)", streams_.size()));
  }
  streams_.insert(stream);
  if (metrics_ != nullptr) metrics_->SetActiveStreams(static_cast<int64_t>(streams_.size()));
  return absl::OkStatus();
}

void GeodexService::UnregisterStream(StreamBase* stream) {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  streams_.erase(stream);
  if (metrics_ != nullptr) metrics_->SetActiveStreams(static_cast<int64_t>(streams_.size()));
}

bool GeodexService::idle() const { return unary_in_flight_ == 0 && active_streams() == 0; }

int64_t GeodexService::active_streams() const {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  return static_cast<int64_t>(streams_.size());
}

void GeodexService::BeginShutdown() {
  std::lock_guard<std::mutex> lock(streams_mutex_);
  if (shutting_down_) return;
  shutting_down_ = true;
  for (StreamBase* stream : streams_) stream->Drain();
}

}  // namespace geodex::server
