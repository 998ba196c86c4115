// End-to-end tests of geodex-server while its model repository changes:
// models added, replaced, removed, corrupt or still loading.

#include <atomic>
#include <chrono>
#include <latch>
#include <map>
#include <set>
#include <thread>

#include "absl/strings/str_format.h"
#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "grpcpp/create_channel.h"
#include "gtest/gtest.h"
#include "server/server_testing.h"

namespace geodex::server {
namespace {

using testing::Context;
using testing::DefaultOptions;
using ::testing::HasSubstr;
using testing::HealthCheck;
using testing::Ref;
using testing::ReferenceEngine;
using testing::TestServer;
using testing::ToProto;

// A second valid sphere index (other sample count): "version 2" of a model.
const std::string& OtherSphereBytes() {
  static const std::string* bytes =
      new std::string(testing::BuildIndexBytes(mesh::gen::Sphere(3, 1.0), 30));
  return *bytes;
}

// --- models changing while serving -----------------------------------------------------

using DistanceStream = grpc::ClientReaderWriter<v1::DistanceBatch, v1::DistanceResult>;

// What a stream of distance batches did: batches sent and read, answers by
// version, batches that failed, answers out of order or wrong.
struct StreamTally {
  std::atomic<int> sent{0};
  std::atomic<int> read{0};
  std::map<int64_t, int> by_version;
  int failed = 0, wrong = 0;
};

// Writes random sphere batches until `stop`, at most 32 in flight: the
// swaps happen while the stream flows, and the backlog left at the end is
// drained well within the deadline however slow the build (sanitizers).
void WriteBatches(DistanceStream& stream, int32_t faces, const std::atomic<bool>& stop,
                  StreamTally& tally) {
  for (int k = 0; !stop; ++k) {
    while (!stop && tally.sent - tally.read >= 32) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (stop) break;
    if (!stream.Write(testing::RandomSphereBatch(k, faces, 50, k, 1000000))) break;
    ++tally.sent;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  stream.WritesDone();
}

// Reads every answer and checks it against the engine of its version.
void ReadAndCheck(DistanceStream& stream, int32_t faces,
                  const std::shared_ptr<const query::QueryEngine>& v1_engine,
                  const std::shared_ptr<const query::QueryEngine>& v2_engine, StreamTally& tally) {
  v1::DistanceResult result;
  while (stream.Read(&result)) {
    const int k = static_cast<int>(result.batch_id());
    if (k != tally.read) ++tally.wrong;
    ++tally.read;
    if (result.error_code() != 0) {
      ++tally.failed;
      ADD_FAILURE() << "batch " << k << ": " << result.error_message();
      continue;
    }
    ++tally.by_version[result.version()];
    auto a = testing::RandomPoints(faces, 50, k), b = testing::RandomPoints(faces, 50, k + 1000000);
    std::vector<double> expected(50);
    const auto& engine = result.version() == 1 ? v1_engine : v2_engine;
    EXPECT_TRUE(engine->DistanceBatch(a, b, expected).ok());
    for (int i = 0; i < 50; ++i) {
      if (result.distances(i) != expected[i]) ++tally.wrong;
    }
  }
}

// Waits (10 s at most) until n more batches have been read.
void WaitForBatches(const StreamTally& tally, int n) {
  const int target = tally.read + n;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (tally.read < target && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

TEST(ServerTest, AddReplaceRemoveWhileStreamingFailsNoBatch) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto v1_engine = ReferenceEngine(testing::SphereIndexBytes());
  auto v2_engine = ReferenceEngine(OtherSphereBytes());
  const int32_t faces = v1_engine->index().num_faces();
  ASSERT_EQ(faces, v2_engine->index().num_faces());

  auto context = Context(60);
  auto stream = stub->StreamDistances(context.get());
  std::atomic<bool> stop{false};
  StreamTally tally;
  std::thread writer([&] { WriteBatches(*stream, faces, stop, tally); });
  std::thread reader([&] { ReadAndCheck(*stream, faces, v1_engine, v2_engine, tally); });
  WaitForBatches(tally, 20);
  testing::WriteModelVersion(ts.root(), "added", 1, testing::TorusIndexBytes());  // add
  ts.Rescan();
  WaitForBatches(tally, 20);
  testing::WriteModelVersion(ts.root(), "sphere", 2, OtherSphereBytes());  // replace
  ts.Rescan();
  WaitForBatches(tally, 20);
  testing::RemoveModel(ts.root(), "torus");  // remove
  ts.Rescan();
  WaitForBatches(tally, 20);
  stop = true;
  writer.join();
  reader.join();
  EXPECT_TRUE(stream->Finish().ok());
  EXPECT_EQ(tally.read, tally.sent.load());
  EXPECT_EQ(tally.failed, 0);
  EXPECT_EQ(tally.wrong, 0);
  EXPECT_GT(tally.by_version[1], 0);
  EXPECT_GT(tally.by_version[2], 0);

  v1::ListModelsResponse list;
  auto c = Context();
  ASSERT_TRUE(stub->ListModels(c.get(), {}, &list).ok());
  std::set<std::string> names;
  for (const auto& m : list.models()) names.insert(m.name());
  EXPECT_EQ(names, (std::set<std::string>{"added", "sphere"}));
}

TEST(ServerTest, CorruptIndexFailsThatModelOnly) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  // A new model whose only version is corrupt (a flipped byte in a section),
  // and a truncated new version of a served model.
  std::string corrupt = OtherSphereBytes();
  corrupt[corrupt.size() / 2] ^= 0x5a;
  testing::WriteModelVersion(ts.root(), "broken", 1, corrupt);
  testing::WriteModelVersion(ts.root(), "sphere", 2,
                             OtherSphereBytes().substr(0, OtherSphereBytes().size() - 100));
  ts.Rescan();

  v1::GetModelRequest get;
  v1::ModelInfo info;
  *get.mutable_model() = Ref("broken");
  auto context = Context();
  ASSERT_TRUE(stub->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::ModelInfo::FAILED);
  EXPECT_THAT(info.reason(), HasSubstr("version 1: DATA_LOSS"));
  EXPECT_THAT(info.reason(), HasSubstr("checksum"));

  *get.mutable_model() = Ref("sphere");
  context = Context();
  ASSERT_TRUE(stub->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::ModelInfo::FAILED);
  EXPECT_THAT(info.reason(), HasSubstr("version 2: DATA_LOSS"));
  EXPECT_EQ(info.version(), 1);  // still served
  EXPECT_EQ(info.available_versions_size(), 2);

  // The broken model is unavailable; the others keep answering.
  v1::DistanceRequest request;
  *request.mutable_a() = ToProto(testing::RandomPoints(100, 3, 1));
  *request.mutable_b() = ToProto(testing::RandomPoints(100, 3, 2));
  v1::DistanceResponse response;
  *request.mutable_model() = Ref("broken");
  context = Context();
  grpc::Status s = stub->Distance(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("failed to load"));
  for (const char* model : {"sphere", "torus"}) {
    *request.mutable_model() = Ref(model);
    context = Context();
    EXPECT_TRUE(stub->Distance(context.get(), request, &response).ok()) << model;
    EXPECT_EQ(response.version(), 1);
  }
  EXPECT_EQ(HealthCheck(ts.TcpChannel(), "broken"), 2);  // NOT_SERVING
  EXPECT_EQ(HealthCheck(ts.TcpChannel(), "sphere"), 1);
}

TEST(ServerTest, LoadingModelIsUnavailable) {
  std::latch entered(1), release(1);
  std::atomic<bool> hold{false};
  TestServer ts([&](ServerOptions& o) {
    o.before_load = [&](const std::string& path) {
      if (hold && path.find("/late/") != std::string::npos) {
        entered.count_down();
        release.wait();
      }
    };
  });
  hold = true;
  testing::WriteModelVersion(ts.root(), "late", 1, testing::SphereIndexBytes());
  ts.server().registry().TriggerRescan();
  entered.wait();
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("late");
  v1::DistanceResponse response;
  auto context = Context();
  grpc::Status s = stub->Distance(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("is loading"));
  v1::GetModelRequest get;
  *get.mutable_model() = Ref("late");
  v1::ModelInfo info;
  context = Context();
  ASSERT_TRUE(stub->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::ModelInfo::LOADING);
  EXPECT_EQ(HealthCheck(ts.TcpChannel(), "late"), 2);
  release.count_down();
  ts.Rescan();
  context = Context();
  ASSERT_TRUE(stub->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::ModelInfo::SERVING);
  EXPECT_EQ(HealthCheck(ts.TcpChannel(), "late"), 1);
}

TEST(ServerTest, HealthIsAliveButNotReadyDuringTheFirstScan) {
  std::latch entered(1), release(1);
  std::atomic<bool> first{true};
  ServerOptions options;
  testing::TempDir dir;
  testing::WriteModelVersion(dir.path(), "sphere", 1, testing::SphereIndexBytes());
  options = DefaultOptions(dir.path());
  options.before_load = [&](const std::string&) {
    if (first.exchange(false)) {
      entered.count_down();
      release.wait();
    }
  };
  auto server = GeodexServer::Start(options);
  ASSERT_TRUE(server.ok()) << server.status();
  entered.wait();
  auto channel = grpc::CreateChannel(absl::StrFormat("127.0.0.1:%d", (*server)->port()),
                                     grpc::InsecureChannelCredentials());
  EXPECT_EQ(HealthCheck(channel, ""), 2);                  // not ready
  EXPECT_EQ(HealthCheck(channel, "geodex.v1.Geodex"), 1);  // alive
  release.count_down();
  (*server)->registry().RescanNow();
  EXPECT_EQ(HealthCheck(channel, ""), 1);
  (*server)->Shutdown(absl::Seconds(1));
  EXPECT_NE(HealthCheck(channel, ""), 1);
}

}  // namespace
}  // namespace geodex::server
