#pragma once

// What every streaming reactor of the Geodex service shares: admission, one
// Finish, and the registration that OnDone removes before the reactor
// deletes itself. Each reactor sees the service only through
// ServiceResources (server/service/service_resources.h).
//
// Ownership: gRPC holds a reactor from the handler's return until OnDone,
// where it deletes itself (the callback API's contract); the StreamSet keeps
// a non-owning registration (for shutdown), removed in OnDone before the
// delete.
//
// Threads: state is guarded by mutex_, and gRPC operations are started
// under it (reactions never run inline in StartRead/StartWrite/Finish, so
// this cannot deadlock). The handler calls Start() once the reactor is fully
// constructed, since a job it submits may run at once.

#include <mutex>

#include "absl/status/status.h"
#include "grpcpp/server_context.h"
#include "server/service/call.h"
#include "server/service/service_resources.h"
#include "server/streams/stream_set.h"

namespace geodex::server {

// `Reactor` is the gRPC reactor type.
template <class Reactor>
class Stream : public Reactor, public StreamBase {
 public:
  // Admits the call (Authorize, then the StreamSet) and starts it with
  // StartLocked(), or finishes it with the error. Returns this, for the
  // handler to hand to gRPC.
  Reactor* Start() {
    absl::Status status = resources_->Authorize(*context_);
    if (status.ok()) status = resources_->streams->Register(this);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!status.ok()) {
      FinishLocked(status);
      return this;
    }
    registered_ = true;
    StartLocked();
    return this;
  }

  void OnDone() final {
    // Wait out a worker that has just released the lock after the call that
    // finished the stream.
    { std::lock_guard<std::mutex> lock(mutex_); }
    if (registered_) resources_->streams->Unregister(this);
    delete this;
  }

 protected:
  // `resources` must outlive the call.
  Stream(const ServiceResources* resources, grpc::CallbackServerContext* context,
         const char* method)
      : resources_(resources), context_(context), call_(StartCall(context, method)) {}

  // The first operations of an admitted call. Holds mutex_.
  virtual void StartLocked() = 0;

  // Finishes the call with `status` unless it has finished already. Holds
  // mutex_.
  void FinishLocked(const absl::Status& status) {
    if (finished_) return;
    finished_ = true;
    this->Finish(resources_->Finish(call_, status));
  }

  // The status of a stream that stops early: CheckAlive's error once the
  // call is over (Cancelled, DeadlineExceeded), else Cancelled(`message`).
  absl::Status StoppedStatus(const char* message) const {
    absl::Status status = CheckAlive(*context_);
    return status.ok() ? absl::CancelledError(message) : status;
  }

  const ServiceResources* const resources_;
  grpc::CallbackServerContext* const context_;
  Call call_;
  std::mutex mutex_;
  bool finished_ = false;

 private:
  bool registered_ = false;
};

}  // namespace geodex::server
