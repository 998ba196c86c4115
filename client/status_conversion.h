#pragma once

// The one place where gRPC status codes become absl::Status (and back, for
// tests and fakes). Nothing else in client/ looks at grpc::Status.

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "grpcpp/support/status.h"

namespace geodex::client {

// The same code and message. grpc::StatusCode and absl::StatusCode share the
// canonical numbering (google.rpc.Code); a value outside it becomes UNKNOWN.
absl::Status FromGrpcStatus(const grpc::Status& status);

// The inverse of FromGrpcStatus.
grpc::Status ToGrpcStatus(const absl::Status& status);

// A per-batch error of a DistanceResult (`error_code` is a google.rpc.Code,
// 0 for OK) as a Status.
absl::Status FromWireCode(int32_t code, const std::string& message);

}  // namespace geodex::client
