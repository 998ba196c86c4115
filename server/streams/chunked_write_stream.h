#pragma once

// A server stream written one message at a time (every server-streaming
// call of the service): a job on the worker pool computes the next message, the
// reactor writes it, and only then is the next one made (backpressure). A
// job and a write are never in flight together and jobs are sequential, so
// what a job fills needs no lock.

#include <cstdint>
#include <mutex>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "grpcpp/support/server_callback.h"
#include "server/service/worker_pool.h"
#include "server/streams/stream.h"

namespace geodex::server {

// Largest payload of one streamed message whose size the server chooses (a
// Matrix block, a field or map chunk).
inline constexpr int64_t kChunkBytes = 1 << 20;

template <class Response>
class ChunkedWriteStream : public Stream<grpc::ServerWriteReactor<Response>> {
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
  ChunkedWriteStream(const ServiceResources* resources, grpc::CallbackServerContext* context,
                     const char* method, const char* unread)
      : Stream<grpc::ServerWriteReactor<Response>>(resources, context, method), unread_(unread) {}

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
    if (!this->resources_->pool->Submit([this](WorkerContext& worker) { Job(worker); })) {
      job_running_ = false;
      this->FinishLocked(this->resources_->Busy());
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

}  // namespace geodex::server
