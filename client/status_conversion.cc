#include "client/status_conversion.h"

namespace geodex::client {

absl::Status FromWireCode(int32_t code, const std::string& message) {
  if (code == 0) return absl::OkStatus();
  // google.rpc.Code runs from 0 (OK) to 16 (UNAUTHENTICATED).
  const auto absl_code =
      code > 0 && code <= 16 ? static_cast<absl::StatusCode>(code) : absl::StatusCode::kUnknown;
  return absl::Status(absl_code, message);
}

absl::Status FromGrpcStatus(const grpc::Status& status) {
  if (status.ok()) return absl::OkStatus();
  return FromWireCode(static_cast<int32_t>(status.error_code()), status.error_message());
}

grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return grpc::Status(static_cast<grpc::StatusCode>(status.code()), std::string(status.message()));
}

}  // namespace geodex::client
