// End-to-end tests of geodex-server's shutdown: streams drained in process,
// and the geodex-server binary's flags and signals (SIGHUP rescans, SIGTERM
// drains).

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_format.h"
#include "gmock/gmock.h"
#include "grpcpp/create_channel.h"
#include "gtest/gtest.h"
#include "server/server_testing.h"

namespace geodex::server {
namespace {

using testing::Context;
using ::testing::HasSubstr;
using testing::Ref;
using testing::TestServer;
using testing::ToProto;

// --- shutdown in process -------------------------------------------------------------

TEST(ServerTest, ShutdownDuringAStreamDrainsIt) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto context = Context(60);
  auto stream = stub->StreamDistances(context.get());
  std::atomic<bool> stop{false};
  std::atomic<int> sent{0};
  std::thread writer([&] {
    for (int k = 0; !stop; ++k) {
      if (!stream->Write(testing::RandomSphereBatch(k, 1280, 200, k, 7))) break;
      ++sent;
    }
  });
  v1::DistanceResult result;
  int read = 0;
  while (read < 50 && stream->Read(&result)) {
    ASSERT_EQ(result.error_code(), 0);
    ++read;
  }
  const auto start = std::chrono::steady_clock::now();
  std::thread shutdown([&] { ts.server().Shutdown(absl::Seconds(10)); });
  while (stream->Read(&result)) {
    EXPECT_EQ(result.error_code(), 0) << result.error_message();  // answered batches are whole
    EXPECT_EQ(result.batch_id(), static_cast<uint64_t>(read));
    ++read;
  }
  stop = true;
  writer.join();
  grpc::Status s = stream->Finish();
  shutdown.join();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE) << s.error_message();
  EXPECT_THAT(s.error_message(), HasSubstr("shutting down"));
  EXPECT_THAT(s.error_message(), HasSubstr(absl::StrFormat("%d batches answered", read)));
  EXPECT_LT(seconds, 5);  // drained, not cut off at the deadline
  // New calls are refused.
  v1::ListModelsResponse list;
  auto c = Context(2);
  EXPECT_FALSE(stub->ListModels(c.get(), {}, &list).ok());
}

TEST(ServerTest, ShutdownFinishesAnIdleStream) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto context = Context(60);
  auto stream = stub->StreamDistances(context.get());
  v1::DistanceBatch batch;
  batch.set_batch_id(1);
  *batch.mutable_model() = Ref("sphere");
  *batch.mutable_a() = ToProto(testing::RandomPoints(1280, 2, 1));
  *batch.mutable_b() = ToProto(testing::RandomPoints(1280, 2, 2));
  ASSERT_TRUE(stream->Write(batch));
  v1::DistanceResult result;
  ASSERT_TRUE(stream->Read(&result));
  const auto start = std::chrono::steady_clock::now();
  ts.server().Shutdown(absl::Seconds(10));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 3);
  EXPECT_FALSE(stream->Read(&result));
  grpc::Status s = stream->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("1 batches answered (last batch id 1)"));
}

// --- the geodex-server binary: flags, SIGHUP, SIGTERM -----------------------------------

// Starts geodex-server with `args`.
testing::ServerProcess Spawn(std::vector<std::string> args) {
  args.insert(args.begin(), GEODEX_SERVER_BINARY);
  return testing::SpawnServer(std::move(args));
}

int ExitCode(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(ServerBinaryTest, BadFlagsExitWithTwo) {
  testing::ServerProcess p = Spawn({"--listen", "127.0.0.1:0"});  // no --models
  EXPECT_EQ(ExitCode(p.pid), 2);
  p = Spawn({"--models", "/nonexistent/dir", "--listen", "127.0.0.1:0"});
  EXPECT_EQ(ExitCode(p.pid), 2);
  testing::TempDir dir;
  p = Spawn({"--models", dir.path(), "--listen", "127.0.0.1:0", "--workers", "-1"});
  EXPECT_EQ(ExitCode(p.pid), 2);
}

TEST(ServerBinaryTest, SighupRescansAndSigtermDrains) {
  testing::TempDir dir;
  testing::WriteModelVersion(dir.path(), "sphere", 1, testing::SphereIndexBytes());
  testing::ServerProcess p =
      Spawn({"--models", dir.path(), "--listen", "127.0.0.1:0", "--poll-seconds", "0", "--workers",
             "1", "--log-level", "warn"});
  ASSERT_GT(p.port, 0);
  auto stub = v1::Geodex::NewStub(grpc::CreateChannel(absl::StrFormat("127.0.0.1:%d", p.port),
                                                      grpc::InsecureChannelCredentials()));
  auto count_serving = [&] {
    v1::ListModelsResponse list;
    auto context = Context(5);
    if (!stub->ListModels(context.get(), {}, &list).ok()) return -1;
    int n = 0;
    for (const auto& m : list.models()) n += m.state() == v1::ModelInfo::SERVING;
    return n;
  };
  auto wait_for = [&](int n) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (count_serving() != n && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return count_serving() == n;
  };
  ASSERT_TRUE(wait_for(1));
  testing::WriteModelVersion(dir.path(), "torus", 1, testing::TorusIndexBytes());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(count_serving(), 1);  // no polling: not seen yet
  kill(p.pid, SIGHUP);
  EXPECT_TRUE(wait_for(2));

  // SIGTERM during a stream: it is drained and the process exits 0.
  auto context = Context(30);
  auto stream = stub->StreamDistances(context.get());
  v1::DistanceBatch batch;
  batch.set_batch_id(5);
  *batch.mutable_model() = Ref("sphere");
  *batch.mutable_a() = ToProto(testing::RandomPoints(1280, 3, 1));
  *batch.mutable_b() = ToProto(testing::RandomPoints(1280, 3, 2));
  ASSERT_TRUE(stream->Write(batch));
  v1::DistanceResult result;
  ASSERT_TRUE(stream->Read(&result));
  EXPECT_EQ(result.error_code(), 0);
  kill(p.pid, SIGTERM);
  EXPECT_FALSE(stream->Read(&result));
  grpc::Status s = stream->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("shutting down"));
  EXPECT_EQ(ExitCode(p.pid), 0);
}

}  // namespace
}  // namespace geodex::server
