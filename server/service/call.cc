#include "server/service/call.h"

#include <algorithm>
#include <atomic>
#include <random>

#include "absl/strings/str_format.h"
#include "server/service/metrics.h"
#include "server/service/status_conversion.h"
#include "spdlog/spdlog.h"

namespace geodex::server {
namespace {

// A client-supplied request id is used when it is short and printable.
bool IsSaneRequestId(grpc::string_ref id) {
  if (id.empty() || id.size() > 64) return false;
  return std::all_of(id.begin(), id.end(), [](char c) { return c > ' ' && c < 127; });
}

std::string NewRequestId() {
  static const uint32_t prefix = std::random_device()();
  static std::atomic<uint64_t> counter{0};
  return absl::StrFormat("%08x-%d", prefix, counter.fetch_add(1) + 1);
}

}  // namespace

Call StartCall(grpc::CallbackServerContext* context, const char* method) {
  Call call;
  call.method = method;
  call.start = Clock::now();
  const auto& metadata = context->client_metadata();
  auto it = metadata.find("x-request-id");
  call.request_id = it != metadata.end() && IsSaneRequestId(it->second)
                        ? std::string(it->second.data(), it->second.size())
                        : NewRequestId();
  context->AddInitialMetadata("x-request-id", call.request_id);
  return call;
}

grpc::Status FinishCall(const Call& call, const absl::Status& status, Metrics* metrics) {
  const double seconds = SecondsSince(call.start);
  if (metrics != nullptr) {
    metrics->RecordCall(call.method, call.model, status.code(), call.pairs, seconds);
  }
  if (!status.ok()) {
    const auto level = IsClientError(status.code()) ? spdlog::level::info : spdlog::level::warn;
    spdlog::log(level, "[{}] {} model='{}' failed after {:.6f}s: {}", call.request_id, call.method,
                call.model, seconds, status.ToString());
  } else {
    spdlog::debug("[{}] {} model='{}' ok: {} items in {:.6f}s", call.request_id, call.method,
                  call.model, call.pairs, seconds);
  }
  return ToGrpcStatus(status);
}

absl::Status CheckAlive(const grpc::CallbackServerContext& context) {
  if (!context.IsCancelled()) return absl::OkStatus();
  if (context.deadline() <= std::chrono::system_clock::now()) {
    return absl::DeadlineExceededError("deadline exceeded");
  }
  return absl::CancelledError("call cancelled");
}

bool IsClientError(absl::StatusCode code) {
  switch (code) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kOutOfRange:
    case absl::StatusCode::kNotFound:
    case absl::StatusCode::kResourceExhausted:
    case absl::StatusCode::kUnauthenticated:
    case absl::StatusCode::kCancelled:
    case absl::StatusCode::kDeadlineExceeded:
      return true;
    default:
      return false;
  }
}

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace geodex::server
