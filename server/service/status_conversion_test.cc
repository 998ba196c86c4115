#include "server/service/status_conversion.h"

#include "gtest/gtest.h"

namespace geodex::server {
namespace {

TEST(StatusConversionTest, KeepsCodeAndMessage) {
  const grpc::Status s = ToGrpcStatus(absl::OutOfRangeError("a[17]: face id 99999"));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::OUT_OF_RANGE);
  EXPECT_EQ(s.error_message(), "a[17]: face id 99999");
  EXPECT_TRUE(ToGrpcStatus(absl::OkStatus()).ok());
}

TEST(StatusConversionTest, EveryCanonicalCodeMapsToTheSameNumber) {
  for (int code = 0; code <= 16; ++code) {
    const absl::Status status(static_cast<absl::StatusCode>(code), code == 0 ? "" : "x");
    EXPECT_EQ(static_cast<int>(ToGrpcStatus(status).error_code()), code);
    EXPECT_EQ(ToRpcCode(status), code);
  }
}

TEST(StatusConversionTest, UnknownCodeBecomesUnknown) {
  const absl::Status status(static_cast<absl::StatusCode>(1234), "odd");
  EXPECT_EQ(ToGrpcStatus(status).error_code(), grpc::StatusCode::UNKNOWN);
}

}  // namespace
}  // namespace geodex::server
