#include "server/streams/exp_map_stream.h"

#include <algorithm>
#include <vector>

#include "core/common/status_macros.h"
#include "server/convert/convert.h"
#include "server/service/service_resources.h"
#include "server/streams/chunked_write_stream.h"

namespace geodex::server {
namespace {

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
    GEODEX_ASSIGN_OR_RETURN(map_, queries.ExpMap(worker.a, 0, options, &worker.scratch));
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
