#include "tests/soak/soak_driver_lib.h"

#include <random>
#include <sstream>
#include <string>

#include "absl/strings/str_format.h"
#include "core/index/index.h"
#include "gmock/gmock.h"
#include "grpcpp/create_channel.h"
#include "gtest/gtest.h"
#include "server/server.h"
#include "server/model_repository_testing.h"
#include "tests/bench/bench_flags.h"
#include "tests/soak/soak_client.h"

namespace geodex::soak {
namespace {

using ::testing::HasSubstr;

TEST(SoakFlagsTest, ValuesAndChecks) {
  SoakOptions options;
  auto app = SoakFlags(&options);
  std::ostringstream out, err;
  ASSERT_EQ(bench::ParseFlags(*app,
                              {"soak_driver", "--server", "h:1", "--model", "m", "--version",
                               "1=a.gdx", "--version", "2=b.gdx", "--threads", "3"},
                              out, err),
            std::nullopt);
  EXPECT_EQ(options.server, "h:1");
  EXPECT_EQ(options.model, "m");
  EXPECT_EQ(options.versions, (std::vector<std::string>{"1=a.gdx", "2=b.gdx"}));
  EXPECT_EQ(options.threads, 3);
  EXPECT_EQ(options.seconds, 30);
  EXPECT_EQ(options.max_pairs, 1000);

  SoakOptions other;
  auto missing = SoakFlags(&other);
  EXPECT_NE(bench::ParseFlags(*missing, {"soak_driver", "--server", "h:1"}, out, err).value_or(0),
            0);
  auto range = SoakFlags(&other);
  EXPECT_NE(bench::ParseFlags(*range,
                              {"soak_driver", "--server", "h:1", "--model", "m", "--version",
                               "1=a.gdx", "--threads", "0"},
                              out, err)
                .value_or(0),
            0);
  auto help = SoakFlags(&other);
  std::ostringstream help_out;
  EXPECT_EQ(bench::ParseFlags(*help, {"soak_driver", "--help"}, help_out, err), 0);
  EXPECT_THAT(help_out.str(), HasSubstr("--max-pairs INT:INT in [1 - 100000]"));
}

TEST(VersionSpecTest, ParsesVersionAndPath) {
  auto spec = ParseVersionSpec("12=/tmp/v 1.gdx");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->first, 12);
  EXPECT_EQ(spec->second, "/tmp/v 1.gdx");
  EXPECT_EQ(ParseVersionSpec("v1.gdx").status().message(), "--version wants V=INDEX, got v1.gdx");
  EXPECT_EQ(ParseVersionSpec("x=v1.gdx").status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(VersionSpecTest, LoadEnginesSaysWhatFailed) {
  auto bad_spec = LoadEngines({"nope"});
  EXPECT_EQ(bad_spec.status().message(), "--version wants V=INDEX, got nope");
  auto missing = LoadEngines({"1=/nonexistent/v1.gdx"});
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(missing.status().message(), HasSubstr("/nonexistent/v1.gdx"));
}

TEST(SummaryTest, LineAndVerdict) {
  EXPECT_EQ(SummaryLine(6, 20, {.valid = 100, .invalid = 30, .violations = 0}),
            "soak_driver: 6 threads, 20 s: 100 valid calls, 30 invalid refused, 0 violations\n");
  std::string failure;
  EXPECT_EQ(Verdict({.valid = 100, .invalid = 30, .violations = 0}, &failure), 0);
  EXPECT_EQ(failure, "");
  EXPECT_EQ(Verdict({.valid = 100, .invalid = 30, .violations = 2}, &failure), 1);
  EXPECT_EQ(failure, "");
  EXPECT_EQ(Verdict({.valid = 5, .invalid = 0, .violations = 0}, &failure), 1);
  EXPECT_EQ(failure,
            "soak_driver: FAILED: 5 valid and 0 invalid calls made: nothing was checked\n");
}

// A server in this process over one model "sphere" of the given version,
// and the clients, whose reference index (of the same sphere) is version 1.
class SoakClientTest : public ::testing::Test {
 protected:
  void Start(int64_t served_version, int64_t max_pairs) {
    server::testing::WriteModelVersion(dir_.path(), "sphere", served_version,
                                       server::testing::SphereIndexBytes());
    server::ServerOptions options;
    options.models_dir = dir_.path();
    options.workers = 2;
    options.poll_interval = absl::ZeroDuration();
    options.limits.max_pairs_per_message = max_pairs;
    auto srv = server::GeodexServer::Start(options);
    ASSERT_TRUE(srv.ok()) << srv.status();
    server_ = *std::move(srv);
    server_->registry().RescanNow();
    auto index = index::Index::FromBytes(server::testing::SphereIndexBytes());
    ASSERT_TRUE(index.ok()) << index.status();
    auto engine = query::QueryEngine::Create(*index);
    ASSERT_TRUE(engine.ok()) << engine.status();
    soak_ = std::make_unique<Soak>(
        grpc::CreateChannel(absl::StrFormat("127.0.0.1:%d", server_->port()),
                            grpc::InsecureChannelCredentials()),
        "sphere", std::map<int64_t, std::shared_ptr<const query::QueryEngine>>{{1, *engine}},
        max_pairs);
  }
  void TearDown() override {
    if (server_ != nullptr) server_->Shutdown(absl::Seconds(5));
  }

  server::testing::TempDir dir_;
  std::unique_ptr<server::GeodexServer> server_;
  std::unique_ptr<Soak> soak_;
};

// Every valid answer equals the offline engine's, every invalid call gets
// its code.
TEST_F(SoakClientTest, ServedAnswersMatchTheOfflineEngine) {
  // A valid Distance call sends at most 64 pairs; the limit sits above.
  ASSERT_NO_FATAL_FAILURE(Start(/*served_version=*/1, /*max_pairs=*/100));
  std::mt19937 rng(7);
  for (int i = 0; i < 40; ++i) soak_->Step(rng);
  const SoakTotals totals = soak_->totals();
  EXPECT_EQ(totals.violations, 0);
  EXPECT_GT(totals.valid, 0);
  EXPECT_GT(totals.invalid, 0);
  std::string failure;
  EXPECT_EQ(Verdict(totals, &failure), 0) << failure;
}

// Answers of a version the driver has no index of are violations.
TEST_F(SoakClientTest, AnAnswerOfAnUnknownVersionIsAViolation) {
  ASSERT_NO_FATAL_FAILURE(Start(/*served_version=*/2, /*max_pairs=*/1000));
  std::mt19937 rng(7);
  ::testing::internal::CaptureStderr();
  for (int i = 0; i < 10; ++i) soak_->Step(rng);
  EXPECT_THAT(::testing::internal::GetCapturedStderr(),
              HasSubstr("answered by version 2, which has no reference index"));
  EXPECT_GT(soak_->totals().violations, 0);
}

}  // namespace
}  // namespace geodex::soak
