#include "server/streams/stream_set.h"

#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::server {
namespace {

using ::testing::HasSubstr;

class CountingStream : public StreamBase {
 public:
  void Drain() override { ++drains; }
  int drains = 0;
};

TEST(StreamSetTest, AdmitsUpToTheLimitAndCountsWhatRuns) {
  ServiceLimits limits;
  limits.max_concurrent_streams = 2;
  StreamSet set(limits, /*metrics=*/nullptr);
  CountingStream a, b, c;
  EXPECT_TRUE(set.Register(&a).ok());
  EXPECT_TRUE(set.Register(&b).ok());
  EXPECT_EQ(set.size(), 2);
  const absl::Status refused = set.Register(&c);
  EXPECT_EQ(refused.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(refused.message()), HasSubstr("max_concurrent_streams"));
  EXPECT_EQ(set.size(), 2);
  set.Unregister(&a);
  EXPECT_EQ(set.size(), 1);
  EXPECT_TRUE(set.Register(&c).ok());
  EXPECT_EQ(set.size(), 2);
}

TEST(StreamSetTest, ShutdownDrainsEveryRegisteredStreamOnceAndAdmitsNoMore) {
  StreamSet set(ServiceLimits(), /*metrics=*/nullptr);
  CountingStream a, b, gone, late;
  ASSERT_TRUE(set.Register(&a).ok());
  ASSERT_TRUE(set.Register(&b).ok());
  ASSERT_TRUE(set.Register(&gone).ok());
  set.Unregister(&gone);
  EXPECT_FALSE(set.shutting_down());
  set.BeginShutdown();
  set.BeginShutdown();  // idempotent
  EXPECT_TRUE(set.shutting_down());
  EXPECT_EQ(a.drains, 1);
  EXPECT_EQ(b.drains, 1);
  EXPECT_EQ(gone.drains, 0);
  const absl::Status refused = set.Register(&late);
  EXPECT_EQ(refused.code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(refused.message()), HasSubstr("server is shutting down"));
  EXPECT_EQ(set.size(), 2);
}

}  // namespace
}  // namespace geodex::server
