#pragma once

// Internal to the GeodexService implementation: what the unary calls
// (geodex_service.cc), the distance stream (geodex_service_distance_stream.cc)
// and the chunked write streams (geodex_service_write_streams.cc) share. Not
// for other users of the service; include server/geodex_service.h.

#include <chrono>
#include <mutex>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "server/geodex_service.h"
#include "server/model_registry.h"

namespace geodex::server {
namespace service_internal {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start);

// Client mistakes are logged at info, the server's own trouble at warn.
bool IsClientError(absl::StatusCode code);

// What a distance request asks of the engine: its near-pair mode (as the
// request says: near_pairs, or the deprecated exact_near_pairs; else as the
// model's configuration says: exact_near_pairs, then unfold_near_pairs; else
// by path length) and its tolerance (the request's, else the model's).
// Errors: InvalidArgument for an unknown mode, a contradiction or a bad
// tolerance.
absl::StatusOr<query::DistanceOptions> DistanceOptionsFor(const ModelSnapshot& model,
                                                          int near_pairs, bool exact_near_pairs,
                                                          double tolerance);

}  // namespace service_internal

// A streaming call's reactor. Ownership: gRPC holds the reactor from the
// handler's return until OnDone, where it deletes itself (the callback API's
// contract); the service keeps a non-owning registration (for
// BeginShutdown), removed in OnDone before the delete, under streams_mutex_.
class GeodexService::StreamBase {
 public:
  virtual ~StreamBase() = default;
  // Called under streams_mutex_ by BeginShutdown.
  virtual void Drain() = 0;
};

// What every streaming reactor shares: admission, one Finish, and the
// registration that OnDone removes before the reactor deletes itself.
// `Reactor` is the gRPC reactor type. State is guarded by mutex_, and gRPC
// operations are started under it (reactions never run inline in StartRead/
// StartWrite/Finish, so this cannot deadlock). The handler calls Start() once
// the reactor is fully constructed, since a job it submits may run at once.
template <class Reactor>
class GeodexService::Stream : public Reactor, public GeodexService::StreamBase {
 public:
  // Admits the call (Authorize, RegisterStream) and starts it with
  // StartLocked(), or finishes it with the error. Returns this, for the
  // handler to hand to gRPC.
  Reactor* Start() {
    absl::Status status = service_->Authorize(*context_);
    if (status.ok()) status = service_->RegisterStream(this);
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
    if (registered_) service_->UnregisterStream(this);
    delete this;
  }

 protected:
  Stream(GeodexService* service, grpc::CallbackServerContext* context, const char* method)
      : service_(service), context_(context), call_(service->StartCall(context, method)) {}

  // The first operations of an admitted call. Holds mutex_.
  virtual void StartLocked() = 0;

  // Finishes the call with `status` unless it has finished already. Holds
  // mutex_.
  void FinishLocked(const absl::Status& status) {
    if (finished_) return;
    finished_ = true;
    this->Finish(service_->FinishCall(call_, status));
  }

  // The status of a stream that stops early: CheckAlive's error once the
  // call is over (Cancelled, DeadlineExceeded), else Cancelled(`message`).
  absl::Status StoppedStatus(const char* message) const {
    absl::Status status = CheckAlive(*context_);
    return status.ok() ? absl::CancelledError(message) : status;
  }

  GeodexService* const service_;
  grpc::CallbackServerContext* const context_;
  Call call_;
  std::mutex mutex_;
  bool finished_ = false;

 private:
  bool registered_ = false;
};

}  // namespace geodex::server
