#include "server/geodex_service.h"

#include <algorithm>
#include <atomic>
#include <deque>
#include <random>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "server/convert.h"
#include "server/model_config.h"
#include "server/status_conversion.h"
#include "spdlog/spdlog.h"

namespace geodex::server {
namespace {

using Clock = std::chrono::steady_clock;

// Largest payload of one streamed Matrix block or DistanceField chunk.
constexpr int64_t kChunkBytes = 1 << 20;

// How a request's near pairs are answered: as the request says (near_pairs,
// or the deprecated exact_near_pairs), else as the model's configuration
// says (exact_near_pairs, then unfold_near_pairs), else by path length (the
// engines' default). Errors: InvalidArgument for an unknown mode or a
// contradiction.
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

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

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

// Client mistakes are logged at info, the server's own trouble at warn.
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
                                             const v1::SurfacePoints& b, int near_pairs,
                                             bool exact_near_pairs, WorkerContext& worker,
                                             google::protobuf::RepeatedField<double>* out) const {
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
  GEODEX_ASSIGN_OR_RETURN(const query::NearPairs mode,
                          NearPairsFor(*model.model, near_pairs, exact_near_pairs));
  GEODEX_ASSIGN_OR_RETURN(const query::QueryEngine* engine, model.version->EngineFor(mode));
  GEODEX_RETURN_IF_ERROR(PointsFromProto(a, "a", *engine, &worker.a));
  GEODEX_RETURN_IF_ERROR(PointsFromProto(b, "b", *engine, &worker.b));
  return engine->DistanceBatch(worker.a, worker.b, ResizeForOutput(out, na), &worker.scratch);
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
                        model, request->a(), request->b(), request->near_pairs(),
                        request->exact_near_pairs(), worker, response->mutable_distances()));
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
        const query::QueryEngine& engine = model.version->engine();
        GEODEX_RETURN_IF_ERROR(PointsFromProto(request->a(), "a", engine, &worker.a));
        GEODEX_RETURN_IF_ERROR(PointsFromProto(request->b(), "b", engine, &worker.b));
        response->mutable_paths()->Reserve(static_cast<int>(na));
        for (int64_t i = 0; i < na; ++i) {
          GEODEX_RETURN_IF_ERROR(CheckAlive(*context));
          absl::StatusOr<std::vector<query::PathPoint>> path =
              engine.Path(worker.a[i], worker.b[i], corridor);
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
        const query::QueryEngine& engine = model.version->engine();
        for (size_t i = 0; i < positions.size(); ++i) {
          absl::StatusOr<query::LocatedPoint> located = engine.Locate(positions[i]);
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

// --- streaming calls ----------------------------------------------------------------

// A streaming call's reactor. Ownership: gRPC holds the reactor from the
// handler's return until OnDone, where it deletes itself (the callback API's
// contract); the service keeps a non-owning registration (for
// BeginShutdown), removed in OnDone before the delete, under streams_mutex_.
class GeodexService::StreamBase {
 public:
  virtual ~StreamBase() = default;
  // Called under streams_mutex_ by BeginShutdown.
  virtual void Drain() = 0;
};

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

// What every streaming reactor shares: admission, one Finish, and the
// registration that OnDone removes before the reactor deletes itself.
// `Reactor` is the gRPC reactor type. State is guarded by mutex_, and gRPC
// operations are started under it (reactions never run inline in StartRead/
// StartWrite/Finish, so this cannot deadlock). The handler calls Start() once
// the reactor is fully constructed, since a job it submits may run at once.
template <class Reactor>
class GeodexService::Stream : public Reactor, public GeodexService::StreamBase {
 public:
  // Admits the call (Authorize, RegisterStream) and starts it with
  // StartLocked(), or finishes it with the error. Returns this, for the
  // handler to hand to gRPC.
  Reactor* Start() {
    absl::Status status = service_->Authorize(*context_);
    if (status.ok()) status = service_->RegisterStream(this);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!status.ok()) {
      FinishLocked(status);
      return this;
    }
    registered_ = true;
    StartLocked();
    return this;
  }

  void OnDone() final {
    // Wait out a worker that has just released the lock after the call that
    // finished the stream.
    { std::lock_guard<std::mutex> lock(mutex_); }
    if (registered_) service_->UnregisterStream(this);
    delete this;
  }

 protected:
  Stream(GeodexService* service, grpc::CallbackServerContext* context, const char* method)
      : service_(service), context_(context), call_(service->StartCall(context, method)) {}

  // The first operations of an admitted call. Holds mutex_.
  virtual void StartLocked() = 0;

  // Finishes the call with `status` unless it has finished already. Holds
  // mutex_.
  void FinishLocked(const absl::Status& status) {
    if (finished_) return;
    finished_ = true;
    this->Finish(service_->FinishCall(call_, status));
  }

  // The status of a stream that stops early: CheckAlive's error once the
  // call is over (Cancelled, DeadlineExceeded), else Cancelled(`message`).
  absl::Status StoppedStatus(const char* message) const {
    absl::Status status = CheckAlive(*context_);
    return status.ok() ? absl::CancelledError(message) : status;
  }

  GeodexService* const service_;
  grpc::CallbackServerContext* const context_;
  Call call_;
  std::mutex mutex_;
  bool finished_ = false;

 private:
  bool registered_ = false;
};

// StreamDistances. Advance() decides the next operations.
class GeodexService::DistanceStream final
    : public GeodexService::Stream<grpc::ServerBidiReactor<v1::DistanceBatch, v1::DistanceResult>> {
 public:
  DistanceStream(GeodexService* service, grpc::CallbackServerContext* context)
      : Stream(service, context, "StreamDistances"),
        window_(std::max<size_t>(1, service->limits_.stream_window)) {}

  void OnReadDone(bool ok) override {
    std::lock_guard<std::mutex> lock(mutex_);
    read_in_flight_ = false;
    std::unique_ptr<Slot> slot = std::move(reading_);
    if (finished_) return;
    if (!ok) {
      reads_done_ = true;  // the client half-closed (or the call ended)
      Advance();
      return;
    }
    slot->received = Clock::now();
    // The first batch naming a model sets the stream's model; later batches
    // may leave it empty.
    if (!slot->request.model().name().empty()) stream_model_ = slot->request.model();
    slot->model = stream_model_;
    Slot* raw = slot.get();
    slots_.push_back(std::move(slot));
    ++jobs_;
    if (!service_->pool_->Submit([this, raw](WorkerContext& worker) { Compute(raw, worker); })) {
      --jobs_;
      SetResult(raw, service_->Busy(), 0);
      raw->done = true;
    }
    Advance();
  }

  void OnWriteDone(bool ok) override {
    std::lock_guard<std::mutex> lock(mutex_);
    write_in_flight_ = false;
    if (ok) {
      slots_.pop_front();
    } else {
      cancelled_ = true;  // the stream broke; nothing more can be written
    }
    Advance();
  }

  void OnCancel() override {
    std::lock_guard<std::mutex> lock(mutex_);
    cancelled_ = true;
    Advance();
  }

  void Drain() override {
    std::lock_guard<std::mutex> lock(mutex_);
    draining_ = true;
    Advance();
  }

 private:
  struct Slot {
    v1::DistanceBatch request;
    v1::DistanceResult result;
    v1::ModelRef model;  // the batch's own or the stream's model
    bool done = false;   // result ready to write
    Clock::time_point received;
  };

  void StartLocked() override { Advance(); }

  // Runs on a worker, without the lock while it computes.
  void Compute(Slot* slot, WorkerContext& worker) {
    bool skip;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      skip = cancelled_;
    }
    absl::Status status;
    int64_t version = 0;
    std::string model_label;
    if (skip) {
      status = absl::CancelledError("call cancelled");
    } else if (slot->model.name().empty()) {
      status = absl::InvalidArgumentError(
          absl::StrFormat("batch %d names no model, and no earlier batch of the stream did",
                          slot->request.batch_id()));
    } else {
      Call batch_call;
      absl::StatusOr<ResolvedModel> model = service_->Resolve(slot->model, batch_call);
      status = model.status();
      if (model.ok()) {
        model_label = model->model->name;
        version = model->version->version();
        status = service_->ComputeDistances(
            *model, slot->request.a(), slot->request.b(), slot->request.near_pairs(),
            slot->request.exact_near_pairs(), worker, slot->result.mutable_distances());
      }
    }
    const int64_t pairs = status.ok() ? PointCount(slot->request.a()) : 0;
    SetResult(slot, status, version);
    if (service_->metrics_ != nullptr) {
      service_->metrics_->RecordBatch(model_label, status.code(), pairs,
                                      SecondsSince(slot->received));
    }
    if (!status.ok() && !skip) {
      const auto level = IsClientError(status.code()) ? spdlog::level::info : spdlog::level::warn;
      spdlog::log(level, "[{}] StreamDistances batch {} model='{}' failed: {}", call_.request_id,
                  slot->request.batch_id(), model_label, status.ToString());
    }
    slot->request.Clear();  // free the input early
    std::lock_guard<std::mutex> lock(mutex_);
    call_.pairs += pairs;
    if (!model_label.empty()) call_.model = model_label;
    slot->done = true;
    --jobs_;
    Advance();
    // Nothing after this point: once the lock is released, OnDone may run.
  }

  void SetResult(Slot* slot, const absl::Status& status, int64_t version) {
    v1::DistanceResult& r = slot->result;
    r.set_batch_id(slot->request.batch_id());
    r.set_version(version);
    if (!status.ok()) {
      r.clear_distances();
      r.set_error_code(ToRpcCode(status));
      r.set_error_message(std::string(status.message()));
    }
  }

  // Starts whatever can start now; finishes when nothing is left. Holds mutex_.
  void Advance() {
    if (finished_) return;
    if (!write_in_flight_ && !cancelled_ && !slots_.empty() && slots_.front()->done) {
      write_in_flight_ = true;
      last_written_ = slots_.front()->result.batch_id();
      ++written_;
      StartWrite(&slots_.front()->result);
    }
    if (!read_in_flight_ && !reads_done_ && !cancelled_ && !draining_ && slots_.size() < window_) {
      read_in_flight_ = true;
      reading_ = std::make_unique<Slot>();
      StartRead(&reading_->request);
    }
    if (write_in_flight_ || jobs_ > 0) return;
    absl::Status status;
    if (cancelled_) {
      status = StoppedStatus("the client stopped reading answers");
    } else if (slots_.empty() && reads_done_) {
      status = absl::OkStatus();
    } else if (slots_.empty() && draining_) {
      // A read may still be pending; gRPC fails it once the call finishes.
      status = absl::UnavailableError(absl::StrFormat(
          "server shutting down: %d batches answered (last batch id %d); send the rest again",
          written_, last_written_));
    } else {
      return;
    }
    FinishLocked(status);
  }

  const size_t window_;

  std::deque<std::unique_ptr<Slot>> slots_;  // read, in order; the front may be being written
  std::unique_ptr<Slot> reading_;            // the slot a pending read fills
  v1::ModelRef stream_model_;
  int jobs_ = 0;  // Compute jobs queued or running
  int64_t written_ = 0;
  uint64_t last_written_ = 0;
  bool read_in_flight_ = false;
  bool write_in_flight_ = false;
  bool reads_done_ = false;
  bool cancelled_ = false;
  bool draining_ = false;
};

grpc::ServerBidiReactor<v1::DistanceBatch, v1::DistanceResult>* GeodexService::StreamDistances(
    grpc::CallbackServerContext* context) {
  return (new DistanceStream(this, context))->Start();
}

// A server stream written one message at a time (Matrix, DistanceField,
// GetMesh): a job on the pool computes the next message, the reactor writes
// it, and only then is the next one made (backpressure). A job and a write
// are never in flight together and jobs are sequential, so what a job fills
// needs no lock.
template <class Response>
class GeodexService::ChunkedWriteStream
    : public GeodexService::Stream<grpc::ServerWriteReactor<Response>> {
 public:
  void OnWriteDone(bool ok) override {
    std::lock_guard<std::mutex> lock(this->mutex_);
    write_in_flight_ = false;
    if (!ok && unread_ != nullptr) {
      cancelled_ = true;
      this->FinishLocked(
          absl::CancelledError(absl::StrFormat("the client stopped reading %s", unread_)));
    } else if (!ok || cancelled_) {
      this->FinishLocked(this->StoppedStatus("call cancelled"));
    } else if (HasMoreLocked()) {
      NextLocked();
    } else {
      this->FinishLocked(absl::OkStatus());
    }
  }

  void OnCancel() override {
    std::lock_guard<std::mutex> lock(this->mutex_);
    cancelled_ = true;
    if (!write_in_flight_ && !job_running_)
      this->FinishLocked(this->StoppedStatus("call cancelled"));
  }

  void Drain() override {}  // finite; bounded by the server's shutdown deadline

 protected:
  // `unread` names the messages in the status of a failed write ("the client
  // stopped reading blocks"); null reports why the call ended instead.
  ChunkedWriteStream(GeodexService* service, grpc::CallbackServerContext* context,
                     const char* method, const char* unread)
      : GeodexService::Stream<grpc::ServerWriteReactor<Response>>(service, context, method),
        unread_(unread) {}

  // Runs on a worker, without the lock: computes the next message.
  virtual absl::Status ComputeNext(WorkerContext& worker) = 0;
  // The message to write next, counted in the call's items, or null when
  // there is none. Called after a successful ComputeNext on a live call (and
  // by NextLocked overrides). Holds mutex_.
  virtual const Response* TakeNextLocked() = 0;
  // True when another message follows the one just written. Holds mutex_.
  virtual bool HasMoreLocked() const = 0;
  // Makes and writes the next message: by default a job computes it. Holds
  // mutex_.
  virtual void NextLocked() { SubmitLocked(); }

  void WriteLocked(const Response* message) {
    write_in_flight_ = true;
    this->StartWrite(message);
  }

 private:
  void StartLocked() final { SubmitLocked(); }

  void SubmitLocked() {
    job_running_ = true;
    if (!this->service_->pool_->Submit([this](WorkerContext& worker) { Job(worker); })) {
      job_running_ = false;
      this->FinishLocked(this->service_->Busy());
    }
  }

  void Job(WorkerContext& worker) {
    const absl::Status status = ComputeNext(worker);
    std::lock_guard<std::mutex> lock(this->mutex_);
    job_running_ = false;
    if (!status.ok()) {
      this->FinishLocked(status);
    } else if (cancelled_) {
      this->FinishLocked(absl::CancelledError("call cancelled"));
    } else if (const Response* message = TakeNextLocked()) {
      WriteLocked(message);
    } else {
      this->FinishLocked(absl::OkStatus());  // nothing to stream
    }
    // Nothing after this point: once the lock is released, OnDone may run.
  }

  const char* const unread_;
  bool job_running_ = false;
  bool write_in_flight_ = false;
  bool cancelled_ = false;
};

// Matrix: each job computes one block of whole rows.
class GeodexService::MatrixStream final : public ChunkedWriteStream<v1::MatrixBlock> {
 public:
  MatrixStream(GeodexService* service, grpc::CallbackServerContext* context,
               const v1::MatrixRequest* request)
      : ChunkedWriteStream(service, context, "Matrix", "blocks"), request_(request) {}

 private:
  // Sets up on the first job.
  absl::Status Prepare() {
    GEODEX_ASSIGN_OR_RETURN(model_, service_->Resolve(request_->model(), call_));
    const ServiceLimits limits = service_->LimitsFor(*model_.model);
    const int64_t s = PointCount(request_->sources()), t = PointCount(request_->targets());
    if (s > 0 && t > limits.max_matrix_cells / s) {
      return absl::ResourceExhaustedError(
          absl::StrFormat("%d sources x %d targets exceed the limit of %d cells (max_matrix_cells)",
                          s, t, limits.max_matrix_cells));
    }
    if (request_->block_rows() < 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("block_rows is negative (%d)", request_->block_rows()));
    }
    GEODEX_ASSIGN_OR_RETURN(const query::NearPairs mode,
                            NearPairsFor(*model_.model, request_->near_pairs(), false));
    GEODEX_ASSIGN_OR_RETURN(engine_, model_.version->EngineFor(mode));
    GEODEX_RETURN_IF_ERROR(PointsFromProto(request_->sources(), "sources", *engine_, &sources_));
    GEODEX_RETURN_IF_ERROR(PointsFromProto(request_->targets(), "targets", *engine_, &targets_));
    // At most kChunkBytes a block, whole rows (at least one).
    block_rows_ = std::max<int64_t>(1, kChunkBytes / 8 / std::max<int64_t>(1, t));
    if (request_->block_rows() > 0)
      block_rows_ = std::min<int64_t>(block_rows_, request_->block_rows());
    prepared_ = true;
    return absl::OkStatus();
  }

  absl::Status ComputeNext(WorkerContext& worker) override {
    GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
    if (!prepared_) GEODEX_RETURN_IF_ERROR(Prepare());
    const int64_t s = static_cast<int64_t>(sources_.size());
    const int64_t t = static_cast<int64_t>(targets_.size());
    if (s == 0) return absl::OkStatus();  // no rows: nothing to stream
    rows_ = std::min(block_rows_, s - next_row_);
    values_.resize(rows_ * t);
    worker.a.resize(t);
    for (int64_t r = 0; r < rows_; ++r) {
      GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
      std::fill(worker.a.begin(), worker.a.end(), sources_[next_row_ + r]);
      GEODEX_RETURN_IF_ERROR(engine_->DistanceBatch(
          worker.a, targets_, std::span<double>(values_.data() + r * t, t), &worker.scratch));
    }
    MatrixBlockToProto(next_row_, rows_, t, values_, model_.version->version(), &block_);
    return absl::OkStatus();
  }

  const v1::MatrixBlock* TakeNextLocked() override {
    if (sources_.empty()) return nullptr;
    next_row_ += rows_;
    call_.pairs += rows_ * static_cast<int64_t>(targets_.size());
    return &block_;
  }

  bool HasMoreLocked() const override { return next_row_ < static_cast<int64_t>(sources_.size()); }

  const v1::MatrixRequest* const request_;

  // Used by one job at a time (jobs are sequential).
  bool prepared_ = false;
  ResolvedModel model_;
  const query::QueryEngine* engine_ = nullptr;
  std::vector<mesh::SurfacePoint> sources_, targets_;
  int64_t block_rows_ = 1;
  int64_t next_row_ = 0;
  int64_t rows_ = 0;  // in block_
  std::vector<double> values_;
  v1::MatrixBlock block_;
};

grpc::ServerWriteReactor<v1::MatrixBlock>* GeodexService::Matrix(
    grpc::CallbackServerContext* context, const v1::MatrixRequest* request) {
  return (new MatrixStream(this, context, request))->Start();
}

// DistanceField: one job computes the whole field; its chunks of at most
// kChunkBytes are then copied out and written one at a time, with no further
// job.
class GeodexService::FieldStream final : public ChunkedWriteStream<v1::DistanceFieldChunk> {
 public:
  FieldStream(GeodexService* service, grpc::CallbackServerContext* context,
              const v1::DistanceFieldRequest* request)
      : ChunkedWriteStream(service, context, "DistanceField", nullptr), request_(request) {}

 private:
  absl::Status ComputeNext(WorkerContext& worker) override {
    GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
    GEODEX_ASSIGN_OR_RETURN(model_, service_->Resolve(request_->model(), call_));
    const ServiceLimits limits = service_->LimitsFor(*model_.model);
    const int64_t n = PointCount(request_->sources());
    if (n > limits.max_field_sources) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "%d sources exceed the limit of %d (max_field_sources)", n, limits.max_field_sources));
    }
    if (n == 0) return absl::InvalidArgumentError("sources: no source given");
    const query::QueryEngine& engine = model_.version->engine();
    GEODEX_RETURN_IF_ERROR(PointsFromProto(request_->sources(), "sources", engine, &worker.a));
    GEODEX_ASSIGN_OR_RETURN(field_, engine.Field(worker.a));
    call_.pairs = n * static_cast<int64_t>(field_.distance.size());
    chunk_vertices_ =
        std::max<int64_t>(1, kChunkBytes / (request_->with_nearest_source() ? 12 : 8));
    return absl::OkStatus();
  }

  const v1::DistanceFieldChunk* TakeNextLocked() override {
    const int64_t n = static_cast<int64_t>(field_.distance.size());
    const int64_t count = std::min(chunk_vertices_, n - next_vertex_);
    FieldChunkToProto(field_, next_vertex_, count, request_->with_nearest_source(),
                      model_.version->version(), &chunk_);
    next_vertex_ += count;
    return &chunk_;
  }

  bool HasMoreLocked() const override {
    return next_vertex_ < static_cast<int64_t>(field_.distance.size());
  }

  void NextLocked() override { WriteLocked(TakeNextLocked()); }

  const v1::DistanceFieldRequest* const request_;

  ResolvedModel model_;
  query::DistanceField field_;
  int64_t chunk_vertices_ = 1;
  int64_t next_vertex_ = 0;
  v1::DistanceFieldChunk chunk_;
};

grpc::ServerWriteReactor<v1::DistanceFieldChunk>* GeodexService::DistanceField(
    grpc::CallbackServerContext* context, const v1::DistanceFieldRequest* request) {
  return (new FieldStream(this, context, request))->Start();
}

// GetMesh: each job copies one chunk out of the mapped index. model_ holds
// the snapshot, and so the mapped index, until the reactor is deleted.
class GeodexService::MeshStream final : public ChunkedWriteStream<v1::MeshChunk> {
 public:
  MeshStream(GeodexService* service, grpc::CallbackServerContext* context,
             const v1::GetMeshRequest* request)
      : ChunkedWriteStream(service, context, "GetMesh", "mesh chunks"),
        request_(request),
        chunk_elements_(std::clamp<int64_t>(service->limits_.mesh_chunk_elements, 1, 1 << 16)) {}

 private:
  absl::Status Prepare() {
    GEODEX_ASSIGN_OR_RETURN(model_, service_->Resolve(request_->model(), call_));
    const index::Index& ix = model_.version->index();
    const auto chunks = [this](int64_t n) { return (n + chunk_elements_ - 1) / chunk_elements_; };
    num_chunks_ = std::max<int64_t>({1, chunks(ix.num_vertices()), chunks(ix.num_faces())});
    prepared_ = true;
    return absl::OkStatus();
  }

  // Copies chunk next_chunk_: vertices and faces from next_chunk_ *
  // chunk_elements_ on (either range may be empty near the end).
  absl::Status ComputeNext(WorkerContext& /*worker*/) override {
    GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
    if (!prepared_) GEODEX_RETURN_IF_ERROR(Prepare());
    const index::Index& ix = model_.version->index();
    const int64_t begin = next_chunk_ * chunk_elements_;
    const int64_t nv = std::clamp<int64_t>(ix.num_vertices() - begin, 0, chunk_elements_);
    const int64_t nf = std::clamp<int64_t>(ix.num_faces() - begin, 0, chunk_elements_);
    const int64_t vertex_offset = std::min<int64_t>(begin, ix.num_vertices());
    const int64_t face_offset = std::min<int64_t>(begin, ix.num_faces());
    MeshChunkToProto(ix, vertex_offset, nv, face_offset, nf, model_.version->version(), &chunk_);
    items_ = nv + nf;
    return absl::OkStatus();
  }

  const v1::MeshChunk* TakeNextLocked() override {
    ++next_chunk_;
    call_.pairs += items_;
    return &chunk_;
  }

  bool HasMoreLocked() const override { return next_chunk_ < num_chunks_; }

  const v1::GetMeshRequest* const request_;
  const int64_t chunk_elements_;

  // Used by one job at a time (jobs are sequential).
  bool prepared_ = false;
  ResolvedModel model_;
  int64_t num_chunks_ = 1;
  int64_t next_chunk_ = 0;
  int64_t items_ = 0;  // vertices and faces in chunk_
  v1::MeshChunk chunk_;
};

grpc::ServerWriteReactor<v1::MeshChunk>* GeodexService::GetMesh(
    grpc::CallbackServerContext* context, const v1::GetMeshRequest* request) {
  return (new MeshStream(this, context, request))->Start();
}

}  // namespace geodex::server
