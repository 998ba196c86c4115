// The server streams written one message at a time: Matrix, DistanceField,
// ExpMap and GetMesh (see "Streams" in server/geodex_service.h).

#include <algorithm>
#include <span>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "server/convert.h"
#include "server/geodex_service.h"
#include "server/geodex_service_stream.h"

namespace geodex::server {
namespace {

// Largest payload of one streamed Matrix block or DistanceField chunk.
constexpr int64_t kChunkBytes = 1 << 20;

}  // namespace

using service_internal::DistanceOptionsFor;

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
    GEODEX_ASSIGN_OR_RETURN(options_, DistanceOptionsFor(*model_.model, request_->near_pairs(),
                                                         false, request_->tolerance()));
    queries_ = &model_.version->queries();
    GEODEX_RETURN_IF_ERROR(PointsFromProto(request_->sources(), "sources", *queries_, &sources_));
    GEODEX_RETURN_IF_ERROR(PointsFromProto(request_->targets(), "targets", *queries_, &targets_));
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
    const bool bounds = request_->error_bounds();
    values_.resize(rows_ * t);
    bounds_.resize(bounds ? rows_ * t : 0);
    for (int64_t r = 0; r < rows_; ++r) {
      GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
      worker.a.AssignRepeated(sources_, next_row_ + r, t);
      GEODEX_RETURN_IF_ERROR(queries_->DistanceBatch(
          worker.a, targets_, std::span<double>(values_.data() + r * t, t), options_,
          &worker.scratch,
          bounds ? std::span<double>(bounds_.data() + r * t, t) : std::span<double>()));
    }
    MatrixBlockToProto(next_row_, rows_, t, values_, model_.version->version(), &block_);
    block_.mutable_bounds()->Assign(bounds_.begin(), bounds_.end());
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
  const query::InputQueries* queries_ = nullptr;
  query::DistanceOptions options_;
  std::vector<double> bounds_;
  query::EnginePoints sources_, targets_;
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

grpc::ServerWriteReactor<v1::DistanceFieldChunk>* GeodexService::DistanceField(
    grpc::CallbackServerContext* context, const v1::DistanceFieldRequest* request) {
  return (new FieldStream(this, context, request))->Start();
}

// ExpMap: one job computes the whole map, then its chunks are written one at
// a time, as DistanceField's.
class GeodexService::ExpMapStream final : public ChunkedWriteStream<v1::ExpMapChunk> {
 public:
  ExpMapStream(GeodexService* service, grpc::CallbackServerContext* context,
               const v1::ExpMapRequest* request)
      : ChunkedWriteStream(service, context, "ExpMap", nullptr), request_(request) {}

 private:
  absl::Status ComputeNext(WorkerContext& worker) override {
    GEODEX_RETURN_IF_ERROR(CheckAlive(*context_));
    GEODEX_ASSIGN_OR_RETURN(model_, service_->Resolve(request_->model(), call_));
    if (PointCount(request_->center()) != 1) {
      return absl::InvalidArgumentError(absl::StrFormat("center: give exactly one point, got %d",
                                                        PointCount(request_->center())));
    }
    const query::InputQueries& queries = model_.version->queries();
    GEODEX_RETURN_IF_ERROR(PointsFromProto(request_->center(), "center", queries, &worker.a));
    query::ExpMapOptions options;
    options.radius = request_->radius();
    const auto& direction = request_->reference_direction().xyz();
    if (direction.size() == 3) {
      options.reference_direction = mesh::Vec3(direction[0], direction[1], direction[2]);
    } else if (!direction.empty()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "reference_direction: give one direction (3 numbers), got %d numbers", direction.size()));
    }
    GEODEX_ASSIGN_OR_RETURN(
        options.distance,
        DistanceOptionsFor(*model_.model, request_->near_pairs(), false, request_->tolerance()));
    // The centre as the request gives it (validated above): the map's θ runs
    // round that input face's normal (InputQueries::ExpMap).
    const mesh::SurfacePoint centre{request_->center().faces(0),
                                    {request_->center().weights(0), request_->center().weights(1),
                                     request_->center().weights(2)}};
    GEODEX_ASSIGN_OR_RETURN(map_, queries.ExpMap(centre, options, &worker.scratch));
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

grpc::ServerWriteReactor<v1::ExpMapChunk>* GeodexService::ExpMap(
    grpc::CallbackServerContext* context, const v1::ExpMapRequest* request) {
  return (new ExpMapStream(this, context, request))->Start();
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
    const query::InputQueries& queries = model_.version->queries();
    const auto chunks = [this](int64_t n) { return (n + chunk_elements_ - 1) / chunk_elements_; };
    num_chunks_ = std::max<int64_t>({1, chunks(queries.num_vertices()), chunks(queries.num_faces())});
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

grpc::ServerWriteReactor<v1::MeshChunk>* GeodexService::GetMesh(
    grpc::CallbackServerContext* context, const v1::GetMeshRequest* request) {
  return (new MeshStream(this, context, request))->Start();
}

}  // namespace geodex::server
