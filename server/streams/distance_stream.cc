#include "server/streams/distance_stream.h"

#include <algorithm>
#include <deque>
#include <memory>
#include <string>

#include "absl/strings/str_format.h"
#include "server/convert/convert.h"
#include "server/service/call.h"
#include "server/service/compute_distances.h"
#include "server/service/metrics.h"
#include "server/service/service_resources.h"
#include "server/service/status_conversion.h"
#include "server/streams/stream.h"
#include "spdlog/spdlog.h"

namespace geodex::server {
namespace {

// Advance() decides the next operations.
class DistanceStream final
    : public Stream<grpc::ServerBidiReactor<v1::DistanceBatch, v1::DistanceResult>> {
 public:
  DistanceStream(const ServiceResources* resources, grpc::CallbackServerContext* context)
      : Stream(resources, context, "StreamDistances"),
        window_(std::max<size_t>(1, resources->limits.stream_window)) {}

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
    if (!resources_->pool->Submit([this, raw](WorkerContext& worker) { Compute(raw, worker); })) {
      --jobs_;
      SetResult(raw, resources_->Busy(), 0);
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
      absl::StatusOr<ResolvedModel> model = resources_->Resolve(slot->model, batch_call);
      status = model.status();
      if (model.ok()) {
        model_label = model->model->name;
        version = model->version->version();
        status = ComputeDistances(*model, resources_->LimitsFor(*model->model), slot->request.a(),
                                  slot->request.b(), DistanceChoice::Of(slot->request), worker,
                                  slot->result.mutable_distances(), slot->result.mutable_bounds());
      }
    }
    const int64_t pairs = status.ok() ? PointCount(slot->request.a()) : 0;
    SetResult(slot, status, version);
    if (resources_->metrics != nullptr) {
      resources_->metrics->RecordBatch(model_label, status.code(), pairs,
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

}  // namespace

grpc::ServerBidiReactor<v1::DistanceBatch, v1::DistanceResult>* StartDistanceStream(
    const ServiceResources* resources, grpc::CallbackServerContext* context) {
  return (new DistanceStream(resources, context))->Start();
}

}  // namespace geodex::server
