// Matrix: the distances from every source to every target, streamed as
// blocks of whole rows (at most 1 MiB of values each, fewer rows when the
// request's block_rows asks). It computes one block on the worker pool,
// writes it, and computes the next only when the write has completed; a
// cancelled call stops between rows.

#include <algorithm>
#include <span>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "server/config/limits.h"
#include "server/convert/convert.h"
#include "server/service/service_resources.h"
#include "server/streams/chunked_write_stream.h"
#include "server/streams/streamed_calls.h"

namespace geodex::server {
namespace {

// Each job computes one block of whole rows.
class MatrixStream final : public ChunkedWriteStream<v1::MatrixBlock> {
 public:
  MatrixStream(const ServiceResources* resources, grpc::CallbackServerContext* context,
               const v1::MatrixRequest* request)
      : ChunkedWriteStream(resources, context, "Matrix", "blocks"), request_(request) {}

 private:
  // Sets up on the first job.
  absl::Status Prepare() {
    GEODEX_ASSIGN_OR_RETURN(model_, resources_->Resolve(request_->model(), call_));
    const int64_t s = PointCount(request_->sources()), t = PointCount(request_->targets());
    GEODEX_RETURN_IF_ERROR(CheckMatrixCells(resources_->LimitsFor(*model_.model), s, t));
    if (request_->block_rows() < 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("block_rows is negative (%d)", request_->block_rows()));
    }
    GEODEX_ASSIGN_OR_RETURN(
        options_, DistanceOptionsFor(model_.model->config, DistanceChoice::Of(*request_)));
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
    MatrixBlockToProto(next_row_, rows_, t, values_, bounds_, model_.version->version(), &block_);
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

}  // namespace

grpc::ServerWriteReactor<v1::MatrixBlock>* StartMatrixStream(const ServiceResources* resources,
                                                             grpc::CallbackServerContext* context,
                                                             const v1::MatrixRequest* request) {
  return (new MatrixStream(resources, context, request))->Start();
}

}  // namespace geodex::server
