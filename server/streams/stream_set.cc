#include "server/streams/stream_set.h"

#include "core/common/status_macros.h"
#include "server/service/metrics.h"

namespace geodex::server {

StreamSet::StreamSet(const ServiceLimits& limits, Metrics* metrics)
    : limits_(limits), metrics_(metrics) {}

absl::Status StreamSet::Register(StreamBase* stream) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (shutting_down_) return absl::UnavailableError("server is shutting down");
  GEODEX_RETURN_IF_ERROR(CheckConcurrentStreams(limits_, static_cast<int64_t>(streams_.size())));
  streams_.insert(stream);
  if (metrics_ != nullptr) metrics_->SetActiveStreams(static_cast<int64_t>(streams_.size()));
  return absl::OkStatus();
}

void StreamSet::Unregister(StreamBase* stream) {
  std::lock_guard<std::mutex> lock(mutex_);
  streams_.erase(stream);
  if (metrics_ != nullptr) metrics_->SetActiveStreams(static_cast<int64_t>(streams_.size()));
}

void StreamSet::BeginShutdown() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (shutting_down_) return;
  shutting_down_ = true;
  for (StreamBase* stream : streams_) stream->Drain();
}

int64_t StreamSet::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int64_t>(streams_.size());
}

}  // namespace geodex::server
