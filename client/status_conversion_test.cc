#include "client/status_conversion.h"

#include "gtest/gtest.h"

namespace geodex::client {
namespace {

TEST(StatusConversion, EveryCanonicalCodeBothWays) {
  for (int code = 1; code <= 16; ++code) {
    const grpc::Status g(static_cast<grpc::StatusCode>(code), "message " + std::to_string(code));
    const absl::Status a = FromGrpcStatus(g);
    EXPECT_EQ(static_cast<int>(a.code()), code);
    EXPECT_EQ(a.message(), "message " + std::to_string(code));
    const grpc::Status back = ToGrpcStatus(a);
    EXPECT_EQ(back.error_code(), g.error_code());
    EXPECT_EQ(back.error_message(), g.error_message());
  }
}

TEST(StatusConversion, NamedCodesLineUp) {
  EXPECT_EQ(FromGrpcStatus(grpc::Status(grpc::StatusCode::NOT_FOUND, "m")),
            absl::NotFoundError("m"));
  EXPECT_EQ(FromGrpcStatus(grpc::Status(grpc::StatusCode::UNAVAILABLE, "m")),
            absl::UnavailableError("m"));
  EXPECT_EQ(FromGrpcStatus(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "m")),
            absl::InvalidArgumentError("m"));
  EXPECT_EQ(FromGrpcStatus(grpc::Status(grpc::StatusCode::OUT_OF_RANGE, "m")),
            absl::OutOfRangeError("m"));
  EXPECT_EQ(FromGrpcStatus(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "m")),
            absl::ResourceExhaustedError("m"));
  EXPECT_EQ(FromGrpcStatus(grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "m")),
            absl::DeadlineExceededError("m"));
}

TEST(StatusConversion, OkAndOutOfRangeCodes) {
  EXPECT_TRUE(FromGrpcStatus(grpc::Status::OK).ok());
  EXPECT_TRUE(ToGrpcStatus(absl::OkStatus()).ok());
  EXPECT_TRUE(FromWireCode(0, "ignored").ok());
  EXPECT_EQ(FromWireCode(5, "gone"), absl::NotFoundError("gone"));
  EXPECT_EQ(FromWireCode(42, "odd").code(), absl::StatusCode::kUnknown);
  EXPECT_EQ(FromWireCode(-1, "odd").code(), absl::StatusCode::kUnknown);
  EXPECT_EQ(FromWireCode(42, "odd").message(), "odd");
}

}  // namespace
}  // namespace geodex::client
