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

  absl::StatusOr<v1::ListModelsResponse> ListModels(const v1::ListModelsRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->ListModels(r); });
  }
  absl::StatusOr<v1::ModelInfo> GetModel(const v1::GetModelRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->GetModel(r); });
  }
  absl::StatusOr<v1::DistanceResponse> Distance(const v1::DistanceRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->Distance(r); });
  }
  std::unique_ptr<DistanceStream> StreamDistances(const StreamOptions& options) override {
    return inner_->StreamDistances(options);
  }
  absl::StatusOr<std::vector<v1::MatrixBlock>> Matrix(const v1::MatrixRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->Matrix(r); });
  }
  absl::StatusOr<v1::PathResponse> Path(const v1::PathRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->Path(r); });
  }
  absl::StatusOr<std::vector<v1::DistanceFieldChunk>> DistanceField(
      const v1::DistanceFieldRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->DistanceField(r); });
  }
  absl::StatusOr<v1::LocateResponse> Locate(const v1::LocateRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->Locate(r); });
  }
  absl::StatusOr<std::vector<v1::MeshChunk>> GetMesh(const v1::GetMeshRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->GetMesh(r); });
  }
  absl::StatusOr<std::vector<v1::ExpMapChunk>> ExpMap(const v1::ExpMapRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->ExpMap(r); });
  }
  absl::StatusOr<v1::TriangulationResponse> GetTriangulation(
      const v1::GetTriangulationRequest& r) override {
    return RetryLoop(policy_, sleep_, [&] { return inner_->GetTriangulation(r); });
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
