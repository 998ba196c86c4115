#pragma once

// The one place where absl::Status becomes a gRPC status. Every handler in
// server/ returns its errors through these functions, so the codes clients see
// are exactly the ones chosen in core and server code (STYLE.md, "Errors").
//
// Thread safety: pure functions.

#include <cstdint>

#include "absl/status/status.h"
#include "grpcpp/support/status.h"

namespace geodex::server {

// The gRPC status with the same code and message. absl::StatusCode and
// grpc::StatusCode share their numbering (both are google.rpc.Code); an
// unknown code becomes UNKNOWN.
grpc::Status ToGrpcStatus(const absl::Status& status);

// The google.rpc.Code number of `status` (0 for OK), as carried in
// DistanceResult.error_code.
int32_t ToRpcCode(const absl::Status& status);

}  // namespace geodex::server
