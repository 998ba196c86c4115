// GeodexService: admission of unary calls and the unary calls themselves;
// the streaming calls start their reactors (server/streams/).

#include "server/geodex_service.h"

#include <algorithm>
#include <memory>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "server/config/model_config.h"
#include "server/convert/convert.h"
#include "server/service/call.h"
#include "server/service/compute_distances.h"
#include "server/streams/distance_stream.h"

namespace geodex::server {
namespace {

absl::Status WithPrefix(const absl::Status& status, const std::string& prefix) {
  return absl::Status(status.code(), prefix + std::string(status.message()));
}

// A unary call's reactor. It counts the call from its start until gRPC is
// done with it (OnDone: the status has been sent or the call has failed), so
// that shutdown knows when every call has really ended. Ownership: gRPC's
// from the handler's return to OnDone, where it deletes itself.
class UnaryReactor final : public grpc::ServerUnaryReactor {
 public:
  explicit UnaryReactor(std::atomic<int64_t>* in_flight) : in_flight_(in_flight) { ++*in_flight_; }
  void OnDone() override {
    --*in_flight_;
    delete this;
  }

 private:
  std::atomic<int64_t>* const in_flight_;
};

}  // namespace

GeodexService::GeodexService(const ModelRegistry* registry, WorkerPool* pool, Metrics* metrics,
                             const TokenAuth* auth, ServiceLimits limits)
    : streams_(limits, metrics),
      resources_{.registry = registry,
                 .pool = pool,
                 .metrics = metrics,
                 .auth = auth,
                 .limits = limits,
                 .streams = &streams_} {}

GeodexService::~GeodexService() = default;

template <class Fn>
grpc::ServerUnaryReactor* GeodexService::RunUnary(grpc::CallbackServerContext* context,
                                                  const char* method, Fn fn) {
  auto* reactor = new UnaryReactor(&unary_in_flight_);
  auto call = std::make_shared<Call>(StartCall(context, method));
  absl::Status status = resources_.Authorize(*context);
  if (status.ok() && streams_.shutting_down()) {
    status = absl::UnavailableError("server is shutting down");
  }
  if (!status.ok()) {
    reactor->Finish(resources_.Finish(*call, status));
    return reactor;
  }
  // The request, response and context live until Finish; the job calls
  // Finish exactly once.
  const bool queued =
      resources_.pool->Submit([this, context, reactor, call, fn](WorkerContext& worker) {
        absl::Status status = CheckAlive(*context);
        if (status.ok()) status = fn(*call, worker);
        reactor->Finish(resources_.Finish(*call, status));
      });
  if (!queued) reactor->Finish(resources_.Finish(*call, resources_.Busy()));
  return reactor;
}

// --- unary calls ------------------------------------------------------------------

grpc::ServerUnaryReactor* GeodexService::ListModels(grpc::CallbackServerContext* context,
                                                    const v1::ListModelsRequest* /*request*/,
                                                    v1::ListModelsResponse* response) {
  return RunUnary(context, "ListModels", [this, response](Call&, WorkerContext&) {
    std::shared_ptr<const RegistrySnapshot> snapshot = resources_.registry->snapshot();
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
    std::shared_ptr<const RegistrySnapshot> snapshot = resources_.registry->snapshot();
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
    GEODEX_ASSIGN_OR_RETURN(ResolvedModel resolved, resources_.Resolve(ref, call));
    ModelInfoToProto(model, resolved.version, response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* GeodexService::Distance(grpc::CallbackServerContext* context,
                                                  const v1::DistanceRequest* request,
                                                  v1::DistanceResponse* response) {
  return RunUnary(
      context, "Distance",
      [this, request, response](Call& call, WorkerContext& worker) -> absl::Status {
        GEODEX_ASSIGN_OR_RETURN(ResolvedModel model, resources_.Resolve(request->model(), call));
        GEODEX_RETURN_IF_ERROR(
            ComputeDistances(model, resources_.LimitsFor(*model.model), request->a(), request->b(),
                             DistanceChoice::Of(*request), worker, response->mutable_distances(),
                             response->mutable_bounds()));
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
        GEODEX_ASSIGN_OR_RETURN(ResolvedModel model, resources_.Resolve(request->model(), call));
        const int64_t n = PointCount(request->a());
        GEODEX_RETURN_IF_ERROR(CheckPathPairs(resources_.LimitsFor(*model.model),
                                              std::max(n, PointCount(request->b()))));
        GEODEX_RETURN_IF_ERROR(CheckPairedUp(request->a(), request->b()));
        GEODEX_ASSIGN_OR_RETURN(const int32_t corridor,
                                PathCorridorFor(model.model->config, *request));
        const query::InputQueries& queries = model.version->queries();
        GEODEX_RETURN_IF_ERROR(PointsFromProto(request->a(), "a", queries, &worker.a));
        GEODEX_RETURN_IF_ERROR(PointsFromProto(request->b(), "b", queries, &worker.b));
        response->mutable_paths()->Reserve(static_cast<int>(n));
        for (int64_t i = 0; i < n; ++i) {
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
        call.pairs = n;
        response->set_version(model.version->version());
        return absl::OkStatus();
      });
}

grpc::ServerUnaryReactor* GeodexService::Locate(grpc::CallbackServerContext* context,
                                                const v1::LocateRequest* request,
                                                v1::LocateResponse* response) {
  return RunUnary(
      context, "Locate", [this, request, response](Call& call, WorkerContext&) -> absl::Status {
        GEODEX_ASSIGN_OR_RETURN(ResolvedModel model, resources_.Resolve(request->model(), call));
        const int64_t n = request->positions().xyz_size() / 3;
        GEODEX_RETURN_IF_ERROR(CheckLocatePositions(resources_.LimitsFor(*model.model), n));
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
  return RunUnary(
      context, "GetTriangulation",
      [this, request, response](Call& call, WorkerContext&) -> absl::Status {
        GEODEX_ASSIGN_OR_RETURN(ResolvedModel model, resources_.Resolve(request->model(), call));
        TriangulationToProto(model.version->queries(), model.version->version(), response);
        call.pairs = model.version->queries().num_vertices();
        return absl::OkStatus();
      });
}

// --- streaming calls ---------------------------------------------------------------

grpc::ServerBidiReactor<v1::DistanceBatch, v1::DistanceResult>* GeodexService::StreamDistances(
    grpc::CallbackServerContext* context) {
  return StartDistanceStream(&resources_, context);
}

#define GEODEX_SERVER_DEFINE_STREAM(Name, Request, Chunk, Start)                                 \
  grpc::ServerWriteReactor<v1::Chunk>* GeodexService::Name(grpc::CallbackServerContext* context, \
                                                           const v1::Request* request) {         \
    return Start(&resources_, context, request);                                                 \
  }
GEODEX_SERVER_STREAMED_CALLS(GEODEX_SERVER_DEFINE_STREAM)
#undef GEODEX_SERVER_DEFINE_STREAM

// --- shutdown ----------------------------------------------------------------------

void GeodexService::BeginShutdown() { streams_.BeginShutdown(); }

int64_t GeodexService::active_streams() const { return streams_.size(); }

bool GeodexService::idle() const { return unary_in_flight_ == 0 && active_streams() == 0; }

}  // namespace geodex::server
