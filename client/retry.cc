#include "client/retry.h"

#include <algorithm>
#include <cmath>

#include "absl/random/random.h"

namespace geodex::client {

bool IsRetryable(const RetryPolicy& policy, const absl::Status& status) {
  switch (status.code()) {
    case absl::StatusCode::kUnavailable:
      return true;
    case absl::StatusCode::kDeadlineExceeded:
      return policy.retry_deadline_exceeded;
    default:
      return false;
  }
}

absl::Duration BackoffDelay(const RetryPolicy& policy, int failed_attempts) {
  const double growth = std::pow(policy.multiplier, std::max(0, failed_attempts - 1));
  const absl::Duration cap = std::min(policy.max_backoff, policy.initial_backoff * growth);
  if (cap <= absl::ZeroDuration()) return absl::ZeroDuration();
  // "Full jitter": spreads the retries of clients that failed together.
  thread_local absl::BitGen gen;
  return cap * absl::Uniform(gen, 0.0, 1.0);
}

absl::Status GaveUp(const absl::Status& status, int attempts) {
  if (attempts <= 1) return status;
  return absl::Status(status.code(),
                      absl::StrCat(status.message(), " (gave up after ", attempts, " attempts)"));
}

namespace {

class RetryingConnection : public GeodexConnection {
 public:
  RetryingConnection(std::shared_ptr<GeodexConnection> inner, RetryPolicy policy, Sleeper sleep)
      : inner_(std::move(inner)), policy_(policy), sleep_(std::move(sleep)) {
    if (!sleep_) sleep_ = [](absl::Duration d) { absl::SleepFor(d); };
  }

#define GEODEX_CLIENT_RETRY_RPC(Name, Request, Result)                        \
  absl::StatusOr<Result> Name(const Request& request) override {              \
    return RetryLoop(policy_, sleep_, [&] { return inner_->Name(request); }); \
  }
  GEODEX_CLIENT_RPCS(GEODEX_CLIENT_RETRY_RPC)
#undef GEODEX_CLIENT_RETRY_RPC

  std::unique_ptr<DistanceStream> StreamDistances(const StreamOptions& options) override {
    return inner_->StreamDistances(options);
  }

 private:
  std::shared_ptr<GeodexConnection> inner_;
  RetryPolicy policy_;
  Sleeper sleep_;
};

}  // namespace

std::shared_ptr<GeodexConnection> MakeRetryingConnection(std::shared_ptr<GeodexConnection> inner,
                                                         RetryPolicy policy, Sleeper sleep) {
  return std::make_shared<RetryingConnection>(std::move(inner), policy, std::move(sleep));
}

}  // namespace geodex::client
