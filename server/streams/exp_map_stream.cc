// ExpMap: the exponential map (geodesic polar coordinates) round one centre,
// every vertex within the request's radius. One job on the worker pool
// computes the whole map; its chunks of at most 1 MiB are then written one
// at a time, as DistanceField's. The request's options and the chunks are
// converted here, beside the reactor (the shared conversions are
// server/convert/convert.h).

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/query/exp_map.h"
#include "server/config/model_config.h"
#include "server/convert/convert.h"
#include "server/service/service_resources.h"
#include "server/streams/chunked_write_stream.h"
#include "server/streams/streamed_calls.h"

namespace geodex::server {
namespace {

// The exponential map's radius, reference direction and distance options
// (as DistanceOptionsFor); the centre is read by OnePointFromProto.
// Errors: InvalidArgument for a reference direction that is not 3 numbers,
// and those of DistanceOptionsFor.
absl::StatusOr<query::ExpMapOptions> ExpMapOptionsFor(const ModelConfig& config,
                                                      const v1::ExpMapRequest& request) {
  query::ExpMapOptions options;
  options.radius = request.radius();
  const auto& direction = request.reference_direction().xyz();
  if (direction.size() == 3) {
    options.reference_direction = mesh::Vec3(direction[0], direction[1], direction[2]);
  } else if (!direction.empty()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "reference_direction: give one direction (3 numbers), got %d numbers", direction.size()));
  }
  GEODEX_ASSIGN_OR_RETURN(options.distance,
                          DistanceOptionsFor(config, {.near_pairs = request.near_pairs(),
                                                      .tolerance = request.tolerance()}));
  return options;
}

// Entries [offset, offset + count) of an exponential map (in input ids) into
// `chunk`, which is cleared first.
void ExpMapChunkToProto(std::span<const query::ExpMapVertex> map, int64_t offset, int64_t count,
                        int64_t version, v1::ExpMapChunk* chunk) {
  chunk->Clear();
  chunk->set_num_vertices(static_cast<int64_t>(map.size()));
  chunk->set_version(version);
  for (const query::ExpMapVertex& e : map.subspan(offset, count)) {
    chunk->add_vertices(e.vertex);
    chunk->add_r(e.r);
    chunk->add_theta(e.theta);
    chunk->add_u(e.u);
    chunk->add_v(e.v);
  }
}

class ExpMapStream final : public ChunkedWriteStream<v1::ExpMapChunk> {
 public:
  ExpMapStream(const ServiceResources* resources, grpc::CallbackServerContext* context,
               const v1::ExpMapRequest* request)
      : ChunkedWriteStream(resources, context, "ExpMap", nullptr), request_(request) {}

 private:
  absl::Status ComputeNext(WorkerContext& worker) override {
    GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
    GEODEX_ASSIGN_OR_RETURN(model_, resources_->Resolve(request_->model(), call_));
    const query::InputQueries& queries = model_.version->queries();
    GEODEX_RETURN_IF_ERROR(OnePointFromProto(request_->center(), "center", queries, &worker.a));
    GEODEX_ASSIGN_OR_RETURN(const query::ExpMapOptions options,
                            ExpMapOptionsFor(model_.model->config, *request_));
    GEODEX_ASSIGN_OR_RETURN(map_, query::ExpMap(queries, worker.a, 0, options, &worker.scratch));
    call_.pairs = static_cast<int64_t>(map_.size());
    return absl::OkStatus();
  }

  const v1::ExpMapChunk* TakeNextLocked() override {
    // vertex, r, theta, u, v: 36 bytes an entry.
    constexpr int64_t kEntries = kChunkBytes / 36;
    const int64_t n = static_cast<int64_t>(map_.size());
    const int64_t count = std::min(kEntries, n - next_);
    ExpMapChunkToProto(map_, next_, count, model_.version->version(), &chunk_);
    next_ += count;
    return &chunk_;
  }

  bool HasMoreLocked() const override { return next_ < static_cast<int64_t>(map_.size()); }

  void NextLocked() override { WriteLocked(TakeNextLocked()); }

  const v1::ExpMapRequest* const request_;

  ResolvedModel model_;
  std::vector<query::ExpMapVertex> map_;
  int64_t next_ = 0;
  v1::ExpMapChunk chunk_;
};

}  // namespace

grpc::ServerWriteReactor<v1::ExpMapChunk>* StartExpMapStream(const ServiceResources* resources,
                                                             grpc::CallbackServerContext* context,
                                                             const v1::ExpMapRequest* request) {
  return (new ExpMapStream(resources, context, request))->Start();
}

}  // namespace geodex::server
