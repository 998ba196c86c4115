#pragma once

// The streaming calls of the Geodex service running now: their admission
// (max_concurrent_streams), the active-streams gauge, and shutdown, which
// stops admitting and drains every registered stream.
//
// Thread safety: every method is safe from any thread.

#include <atomic>
#include <cstdint>
#include <mutex>
#include <set>

#include "absl/status/status.h"
#include "server/config/limits.h"

namespace geodex::server {

class Metrics;

// A streaming call as the set sees it.
class StreamBase {
 public:
  virtual ~StreamBase() = default;
  // Shutdown has begun: finish soon (StreamDistances stops reading). Called
  // under the set's mutex; must not call back into the set.
  virtual void Drain() = 0;
};

class StreamSet {
 public:
  // `metrics` may be null; it must outlive the set.
  StreamSet(const ServiceLimits& limits, Metrics* metrics);
  StreamSet(const StreamSet&) = delete;
  StreamSet& operator=(const StreamSet&) = delete;

  // Admits `stream` (not owned; registered until Unregister). Errors:
  // Unavailable while shutting down; ResourceExhausted beyond
  // max_concurrent_streams.
  absl::Status Register(StreamBase* stream);
  void Unregister(StreamBase* stream);

  // Stops admitting and drains every registered stream. Returns at once;
  // idempotent.
  void BeginShutdown();
  bool shutting_down() const { return shutting_down_; }
  // Streams registered now.
  int64_t size() const;

 private:
  const ServiceLimits limits_;
  Metrics* const metrics_;
  mutable std::mutex mutex_;
  std::set<StreamBase*> streams_;  // registered, not owned
  std::atomic<bool> shutting_down_{false};
};

}  // namespace geodex::server
