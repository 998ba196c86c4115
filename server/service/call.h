#pragma once

// One call of the Geodex service, unary or streaming: its request id, the
// model and work items its metrics count, and the one log line of an error.
//
// Thread safety: the functions are; a Call is owned by one call at a time.

#include <chrono>
#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/status.h"

namespace geodex::server {

class Metrics;

using Clock = std::chrono::steady_clock;

// What a call's log lines and metrics need.
struct Call {
  const char* method = "";
  std::string request_id;
  std::string model;  // metrics label: a resolved model's name, else ""
  int64_t pairs = 0;  // work items answered
  Clock::time_point start;
};

// Starts `method`: names the call (the client's x-request-id if it sent a
// sane one, else a new id) and echoes the id in the initial metadata.
Call StartCall(grpc::CallbackServerContext* context, const char* method);

// Ends `call` with `status`: records it in `metrics` (may be null), logs an
// error once (client mistakes at info, the server's own trouble at warn),
// and returns the status for gRPC (server/service/status_conversion.h).
grpc::Status FinishCall(const Call& call, const absl::Status& status, Metrics* metrics);

// OK while the call runs; Cancelled or DeadlineExceeded once it is over.
absl::Status CheckAlive(const grpc::CallbackServerContext& context);

// True for the codes of a client's mistake (logged at info, not warn).
bool IsClientError(absl::StatusCode code);

double SecondsSince(Clock::time_point start);

}  // namespace geodex::server
