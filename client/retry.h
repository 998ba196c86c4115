#pragma once

// Retry loop and backoff shared by RetryingConnection and Client::Distance.

#include <functional>
#include <memory>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/time/time.h"
#include "geodex/client/connection.h"
#include "geodex/client/options.h"

namespace geodex::client {

// Sleeps for a duration; tests substitute one that records and returns.
using Sleeper = std::function<void(absl::Duration)>;

// True when `status` may succeed if tried again under `policy`.
bool IsRetryable(const RetryPolicy& policy, const absl::Status& status);

// The wait before attempt `failed_attempts` + 1: uniform in
// [0, min(max_backoff, initial_backoff * multiplier^(failed_attempts - 1))].
absl::Duration BackoffDelay(const RetryPolicy& policy, int failed_attempts);

// `status` with " (gave up after N attempts)" appended to its message.
absl::Status GaveUp(const absl::Status& status, int attempts);

// Calls `f` (returning absl::Status or absl::StatusOr<T>) until it succeeds,
// fails with a non-retryable error, or max_attempts calls were made.
template <typename F>
auto RetryLoop(const RetryPolicy& policy, const Sleeper& sleep, F&& f) -> decltype(f()) {
  for (int attempt = 1;; ++attempt) {
    auto result = f();
    absl::Status status;
    if constexpr (std::is_same_v<decltype(result), absl::Status>) {
      status = result;
    } else {
      status = result.status();
    }
    if (status.ok() || !IsRetryable(policy, status)) return result;
    if (attempt >= policy.max_attempts) {
      return GaveUp(status, attempt);
    }
    sleep(BackoffDelay(policy, attempt));
  }
}

// A connection that retries every call of `inner` under `policy`, except
// StreamDistances (a stream cannot be replayed transparently; Client::Distance
// resumes its own streams). A server-streaming call is retried as a whole.
// Thread-safe if `inner` is.
std::shared_ptr<GeodexConnection> MakeRetryingConnection(std::shared_ptr<GeodexConnection> inner,
                                                         RetryPolicy policy,
                                                         Sleeper sleep = nullptr);

}  // namespace geodex::client
