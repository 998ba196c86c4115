#include "server/streams/field_stream.h"

#include <algorithm>

#include "core/common/status_macros.h"
#include "server/convert.h"
#include "server/limits.h"
#include "server/service_resources.h"
#include "server/streams/chunked_write_stream.h"

namespace geodex::server {
namespace {

// One job computes the field; its chunks are copied out and written with no
// further job.
class FieldStream final : public ChunkedWriteStream<v1::DistanceFieldChunk> {
 public:
  FieldStream(const ServiceResources* resources, grpc::CallbackServerContext* context,
              const v1::DistanceFieldRequest* request)
      : ChunkedWriteStream(resources, context, "DistanceField", nullptr), request_(request) {}

 private:
  absl::Status ComputeNext(WorkerContext& worker) override {
    GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
    GEODEX_ASSIGN_OR_RETURN(model_, resources_->Resolve(request_->model(), call_));
    const int64_t n = PointCount(request_->sources());
    GEODEX_RETURN_IF_ERROR(CheckFieldSources(resources_->LimitsFor(*model_.model), n));
    if (n == 0) return absl::InvalidArgumentError("sources: no source given");
    const query::InputQueries& queries = model_.version->queries();
    GEODEX_RETURN_IF_ERROR(PointsFromProto(request_->sources(), "sources", queries, &worker.a));
    GEODEX_ASSIGN_OR_RETURN(field_, queries.Field(worker.a));
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

}  // namespace

grpc::ServerWriteReactor<v1::DistanceFieldChunk>* StartFieldStream(
    const ServiceResources* resources, grpc::CallbackServerContext* context,
    const v1::DistanceFieldRequest* request) {
  return (new FieldStream(resources, context, request))->Start();
}

}  // namespace geodex::server
