#include "client/retry.h"

#include <vector>

#include "geodex/client/mocks/mock_geodex_connection.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client {
namespace {

using ::testing::HasSubstr;
using ::testing::Return;

struct RecordingSleeper {
  std::vector<absl::Duration> waits;
  Sleeper sleeper() {
    return [this](absl::Duration d) { waits.push_back(d); };
  }
};

TEST(RetryingConnection, RetriesUnavailableUntilSuccess) {
  auto mock = std::make_shared<MockGeodexConnection>();
  v1::ModelInfo info;
  info.set_name("torus");
  EXPECT_CALL(*mock, GetModel)
      .WillOnce(Return(absl::UnavailableError("loading")))
      .WillOnce(Return(absl::UnavailableError("loading")))
      .WillOnce(Return(info));
  RecordingSleeper sleep;
  RetryPolicy policy;
  auto connection = MakeRetryingConnection(mock, policy, sleep.sleeper());
  absl::StatusOr<v1::ModelInfo> result = connection->GetModel({});
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->name(), "torus");
  ASSERT_EQ(sleep.waits.size(), 2u);
  EXPECT_LE(sleep.waits[0], policy.initial_backoff);
  EXPECT_LE(sleep.waits[1], policy.initial_backoff * policy.multiplier);
}

TEST(RetryingConnection, GivesUpAfterMaxAttemptsKeepingTheCode) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Distance).Times(4).WillRepeatedly(Return(absl::UnavailableError("down")));
  RecordingSleeper sleep;
  auto connection = MakeRetryingConnection(mock, RetryPolicy{}, sleep.sleeper());
  absl::StatusOr<v1::DistanceResponse> result = connection->Distance({});
  EXPECT_EQ(result.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(result.status().message(), "down (gave up after 4 attempts)");
  EXPECT_EQ(sleep.waits.size(), 3u);
}

class NotRetried : public ::testing::TestWithParam<absl::StatusCode> {};

TEST_P(NotRetried, OneAttemptAndTheErrorUnchanged) {
  auto mock = std::make_shared<MockGeodexConnection>();
  const absl::Status error(GetParam(), "server says no");
  EXPECT_CALL(*mock, Path).WillOnce(Return(error));
  RecordingSleeper sleep;
  auto connection = MakeRetryingConnection(mock, RetryPolicy{}, sleep.sleeper());
  EXPECT_EQ(connection->Path({}).status(), error);
  EXPECT_TRUE(sleep.waits.empty());
}

INSTANTIATE_TEST_SUITE_P(
    Codes, NotRetried,
    ::testing::Values(absl::StatusCode::kInvalidArgument, absl::StatusCode::kNotFound,
                      absl::StatusCode::kOutOfRange, absl::StatusCode::kResourceExhausted,
                      absl::StatusCode::kFailedPrecondition, absl::StatusCode::kDataLoss,
                      absl::StatusCode::kDeadlineExceeded, absl::StatusCode::kCancelled,
                      absl::StatusCode::kUnauthenticated, absl::StatusCode::kPermissionDenied,
                      absl::StatusCode::kInternal, absl::StatusCode::kUnknown));

TEST(RetryingConnection, DeadlineExceededRetriedOnlyWhenAskedFor) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Locate)
      .WillOnce(Return(absl::DeadlineExceededError("slow")))
      .WillOnce(Return(v1::LocateResponse()));
  RecordingSleeper sleep;
  RetryPolicy policy;
  policy.retry_deadline_exceeded = true;
  auto connection = MakeRetryingConnection(mock, policy, sleep.sleeper());
  EXPECT_TRUE(connection->Locate({}).ok());
  EXPECT_EQ(sleep.waits.size(), 1u);
}

TEST(RetryingConnection, GetTriangulationIsRetriedWhenUnavailable) {
  auto mock = std::make_shared<MockGeodexConnection>();
  v1::TriangulationResponse answer;
  answer.set_version(3);
  EXPECT_CALL(*mock, GetTriangulation)
      .WillOnce(Return(absl::UnavailableError("loading")))
      .WillOnce(Return(answer));
  RecordingSleeper sleep;
  auto connection = MakeRetryingConnection(mock, RetryPolicy{}, sleep.sleeper());
  absl::StatusOr<v1::TriangulationResponse> got = connection->GetTriangulation({});
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(got->version(), 3);
  EXPECT_EQ(sleep.waits.size(), 1u);
}

TEST(RetryingConnection, ServerStreamsAreRetriedWhole) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Matrix)
      .WillOnce(Return(absl::UnavailableError("reset")))
      .WillOnce(Return(std::vector<v1::MatrixBlock>(3)));
  EXPECT_CALL(*mock, DistanceField)
      .WillOnce(Return(absl::UnavailableError("reset")))
      .WillOnce(Return(std::vector<v1::DistanceFieldChunk>(2)));
  EXPECT_CALL(*mock, GetMesh)
      .WillOnce(Return(absl::UnavailableError("reset")))
      .WillOnce(Return(std::vector<v1::MeshChunk>(4)));
  RecordingSleeper sleep;
  auto connection = MakeRetryingConnection(mock, RetryPolicy{}, sleep.sleeper());
  EXPECT_EQ(connection->Matrix({})->size(), 3u);
  EXPECT_EQ(connection->DistanceField({})->size(), 2u);
  EXPECT_EQ(connection->GetMesh({})->size(), 4u);
}

TEST(RetryingConnection, StreamDistancesIsPassedThrough) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, StreamDistances).WillOnce([](const StreamOptions&) {
    return std::make_unique<MockDistanceStream>();
  });
  auto connection = MakeRetryingConnection(mock, RetryPolicy{}, RecordingSleeper().sleeper());
  EXPECT_NE(connection->StreamDistances({}), nullptr);
}

TEST(RetryingConnection, OneAttemptMeansNoRetry) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, ListModels).WillOnce(Return(absl::UnavailableError("down")));
  RetryPolicy policy;
  policy.max_attempts = 1;
  auto connection = MakeRetryingConnection(mock, policy, RecordingSleeper().sleeper());
  EXPECT_EQ(connection->ListModels({}).status(), absl::UnavailableError("down"));
}

TEST(Backoff, FullJitterUnderAnExponentialCap) {
  RetryPolicy policy;
  policy.initial_backoff = absl::Milliseconds(10);
  policy.multiplier = 2;
  policy.max_backoff = absl::Milliseconds(50);
  for (int attempt = 1; attempt <= 5; ++attempt) {
    const absl::Duration cap =
        std::min(policy.max_backoff, policy.initial_backoff * (1 << (attempt - 1)));
    absl::Duration lo = absl::InfiniteDuration(), hi = absl::ZeroDuration();
    for (int i = 0; i < 2000; ++i) {
      const absl::Duration d = BackoffDelay(policy, attempt);
      ASSERT_GE(d, absl::ZeroDuration());
      ASSERT_LE(d, cap);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    // Spread over the whole interval, not a fixed wait.
    EXPECT_LT(lo, cap * 0.05) << attempt;
    EXPECT_GT(hi, cap * 0.95) << attempt;
  }
}

TEST(Backoff, RetryableCodes) {
  RetryPolicy policy;
  EXPECT_TRUE(IsRetryable(policy, absl::UnavailableError("")));
  EXPECT_FALSE(IsRetryable(policy, absl::DeadlineExceededError("")));
  EXPECT_FALSE(IsRetryable(policy, absl::OkStatus()));
  policy.retry_deadline_exceeded = true;
  EXPECT_TRUE(IsRetryable(policy, absl::DeadlineExceededError("")));
  EXPECT_THAT(std::string(GaveUp(absl::UnavailableError("x"), 3).message()),
              HasSubstr("gave up after 3 attempts"));
}

}  // namespace
}  // namespace geodex::client
