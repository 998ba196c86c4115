// GetMesh: the input mesh (the mesh file's vertices and faces) in chunks of
// at most ServiceLimits::mesh_chunk_elements vertices and as many faces. It
// copies one chunk of the mapped index on the worker pool, writes it, and
// copies the next only when the write has completed; the resolved model
// (and so the mapped index) stays alive until the stream ends, even if the
// version is swapped out meanwhile.

#include <algorithm>

#include "core/common/status_macros.h"
#include "server/convert/convert.h"
#include "server/service/service_resources.h"
#include "server/streams/chunked_write_stream.h"
#include "server/streams/streamed_calls.h"

namespace geodex::server {
namespace {

// Each job copies one chunk out of the mapped index. model_ holds the
// snapshot, and so the mapped index, until the reactor is deleted.
class MeshStream final : public ChunkedWriteStream<v1::MeshChunk> {
 public:
  MeshStream(const ServiceResources* resources, grpc::CallbackServerContext* context,
             const v1::GetMeshRequest* request)
      : ChunkedWriteStream(resources, context, "GetMesh", "mesh chunks"),
        request_(request),
        chunk_elements_(std::clamp<int64_t>(resources->limits.mesh_chunk_elements, 1, 1 << 16)) {}

 private:
  absl::Status Prepare() {
    GEODEX_ASSIGN_OR_RETURN(model_, resources_->Resolve(request_->model(), call_));
    const query::InputQueries& queries = model_.version->queries();
    const auto chunks = [this](int64_t n) { return (n + chunk_elements_ - 1) / chunk_elements_; };
    num_chunks_ =
        std::max<int64_t>({1, chunks(queries.num_vertices()), chunks(queries.num_faces())});
    prepared_ = true;
    return absl::OkStatus();
  }

  // Copies chunk next_chunk_: vertices and faces from next_chunk_ *
  // chunk_elements_ on (either range may be empty near the end).
  absl::Status ComputeNext(WorkerContext& /*worker*/) override {
    GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
    if (!prepared_) GEODEX_RETURN_IF_ERROR(Prepare());
    // The input mesh: the file's vertices and faces (core/query/input_queries.h).
    const query::InputQueries& queries = model_.version->queries();
    const int64_t num_vertices = queries.num_vertices();
    const int64_t num_faces = queries.num_faces();
    const int64_t begin = next_chunk_ * chunk_elements_;
    const int64_t nv = std::clamp<int64_t>(num_vertices - begin, 0, chunk_elements_);
    const int64_t nf = std::clamp<int64_t>(num_faces - begin, 0, chunk_elements_);
    const int64_t vertex_offset = std::min<int64_t>(begin, num_vertices);
    const int64_t face_offset = std::min<int64_t>(begin, num_faces);
    MeshChunkToProto(queries, vertex_offset, nv, face_offset, nf, model_.version->version(),
                     &chunk_);
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

}  // namespace

grpc::ServerWriteReactor<v1::MeshChunk>* StartGetMeshStream(const ServiceResources* resources,
                                                            grpc::CallbackServerContext* context,
                                                            const v1::GetMeshRequest* request) {
  return (new MeshStream(resources, context, request))->Start();
}

}  // namespace geodex::server
