// DistanceField: the distance of every vertex of the input mesh from its
// nearest source, or, with a radius, the exact distances of the vertices
// within it (sparse chunks: vertices with their distances). One job on the
// worker pool computes the whole field; its chunks of at most 1 MiB are then
// written one at a time.

#include <algorithm>

#include "core/common/status_macros.h"
#include "server/config/limits.h"
#include "server/convert/convert.h"
#include "server/service/service_resources.h"
#include "server/streams/chunked_write_stream.h"
#include "server/streams/streamed_calls.h"

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
  bool within_radius() const { return request_->radius() != 0; }

  absl::Status ComputeNext(WorkerContext& worker) override {
    GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
    GEODEX_ASSIGN_OR_RETURN(model_, resources_->Resolve(request_->model(), call_));
    const ServiceLimits limits = resources_->LimitsFor(*model_.model);
    const int64_t n = PointCount(request_->sources());
    GEODEX_RETURN_IF_ERROR(CheckFieldSources(limits, n));
    if (n == 0) return absl::InvalidArgumentError("sources: no source given");
    const query::InputQueries& queries = model_.version->queries();
    GEODEX_RETURN_IF_ERROR(PointsFromProto(request_->sources(), "sources", queries, &worker.a));
    const bool nearest = request_->with_nearest_source();
    if (within_radius()) {
      query::FieldWithinOptions options;
      options.radius = request_->radius();
      options.max_vertices = limits.max_field_vertices;
      absl::StatusOr<query::RadiusField> field =
          queries.FieldWithin(worker.a, options, &worker.scratch);
      if (absl::IsResourceExhausted(field.status())) {
        return FieldVerticesExceeded(limits, field.status());
      }
      GEODEX_ASSIGN_OR_RETURN(radius_field_, std::move(field));
      call_.pairs = static_cast<int64_t>(radius_field_.vertices.size());
      // vertex, distance (and nearest source): 12 or 16 bytes an entry.
      chunk_vertices_ = kChunkBytes / (nearest ? 16 : 12);
      return absl::OkStatus();
    }
    GEODEX_ASSIGN_OR_RETURN(field_, queries.Field(worker.a));
    call_.pairs = n * static_cast<int64_t>(field_.distance.size());
    chunk_vertices_ = std::max<int64_t>(1, kChunkBytes / (nearest ? 12 : 8));
    return absl::OkStatus();
  }

  int64_t size() const {
    return static_cast<int64_t>(within_radius() ? radius_field_.vertices.size()
                                                : field_.distance.size());
  }

  const v1::DistanceFieldChunk* TakeNextLocked() override {
    const int64_t count = std::min(chunk_vertices_, size() - next_vertex_);
    if (within_radius()) {
      RadiusFieldChunkToProto(radius_field_, next_vertex_, count, request_->with_nearest_source(),
                              model_.version->version(), &chunk_);
    } else {
      FieldChunkToProto(field_, next_vertex_, count, request_->with_nearest_source(),
                        model_.version->version(), &chunk_);
    }
    next_vertex_ += count;
    return &chunk_;
  }

  bool HasMoreLocked() const override { return next_vertex_ < size(); }

  void NextLocked() override { WriteLocked(TakeNextLocked()); }

  const v1::DistanceFieldRequest* const request_;

  ResolvedModel model_;
  query::DistanceField field_;
  query::RadiusField radius_field_;  // with a radius
  int64_t chunk_vertices_ = 1;
  int64_t next_vertex_ = 0;
  v1::DistanceFieldChunk chunk_;
};

}  // namespace

grpc::ServerWriteReactor<v1::DistanceFieldChunk>* StartDistanceFieldStream(
    const ServiceResources* resources, grpc::CallbackServerContext* context,
    const v1::DistanceFieldRequest* request) {
  return (new FieldStream(resources, context, request))->Start();
}

}  // namespace geodex::server
