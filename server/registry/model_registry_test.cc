#include "server/registry/model_registry.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <latch>
#include <thread>

#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/model_repository_testing.h"

namespace geodex::server {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

class ModelRegistryTest : public ::testing::Test {
 protected:
  void Start(RegistryOptions options = {}) {
    options.root = dir_.path();
    if (options.poll_interval == absl::Seconds(10)) options.poll_interval = absl::ZeroDuration();
    auto registry = ModelRegistry::Create(options);
    ASSERT_TRUE(registry.ok()) << registry.status();
    registry_ = *std::move(registry);
    registry_->Start();
    registry_->RescanNow();
  }
  std::shared_ptr<const ModelSnapshot> Model(const std::string& name) {
    auto snapshot = registry_->snapshot();
    auto it = snapshot->models.find(name);
    return it == snapshot->models.end() ? nullptr : it->second;
  }
  void Write(const std::string& model, int64_t version, const std::string& bytes) {
    testing::WriteModelVersion(dir_.path(), model, version, bytes);
  }
  // A valid index that is not the sphere's bytes (another sample count).
  static const std::string& OtherSphereBytes() {
    static const std::string* bytes =
        new std::string(testing::BuildIndexBytes(mesh::gen::Sphere(3, 1.0), 30));
    return *bytes;
  }

  testing::TempDir dir_;
  std::unique_ptr<ModelRegistry> registry_;
};

TEST_F(ModelRegistryTest, CreateChecksTheRoot) {
  RegistryOptions options;
  options.root = dir_.path() + "/missing";
  EXPECT_EQ(ModelRegistry::Create(options).status().code(), absl::StatusCode::kNotFound);
  std::ofstream(dir_.path() + "/file") << "x";
  options.root = dir_.path() + "/file";
  EXPECT_EQ(ModelRegistry::Create(options).status().code(), absl::StatusCode::kFailedPrecondition);
}

TEST_F(ModelRegistryTest, ServesTheNewestVersion) {
  Write("sphere", 1, testing::SphereIndexBytes());
  Write("sphere", 2, OtherSphereBytes());
  Start();
  auto m = Model("sphere");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->state, LoadState::kServing);
  EXPECT_THAT(m->available_versions, ElementsAre(1, 2));
  auto resolved = registry_->Resolve("sphere", 0);
  ASSERT_TRUE(resolved.ok()) << resolved.status();
  EXPECT_EQ(resolved->version->version(), 2);
  EXPECT_EQ(resolved->version->index().num_samples(), 30);
  EXPECT_TRUE(resolved->version->index().is_mapped());
  // Only the newest is served by default; a pinned older version is named.
  auto pinned = registry_->Resolve("sphere", 1);
  EXPECT_EQ(pinned.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(pinned.status().message()), HasSubstr("served: 2; on disk: 1, 2"));
}

TEST_F(ModelRegistryTest, KeepVersionsServesSeveral) {
  Write("sphere", 1, testing::SphereIndexBytes());
  Write("sphere", 2, OtherSphereBytes());
  testing::WriteModelConfig(dir_.path(), "sphere", "keep_versions: 2\n");
  Start();
  auto v1 = registry_->Resolve("sphere", 1);
  ASSERT_TRUE(v1.ok()) << v1.status();
  EXPECT_EQ(v1->version->index().num_samples(), 40);
  EXPECT_EQ(registry_->Resolve("sphere", 0)->version->version(), 2);
  EXPECT_EQ(registry_->Resolve("sphere", 7).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(ModelRegistryTest, RejectsBadNamesAndIgnoresBadDirectories) {
  Write("good", 1, testing::SphereIndexBytes());
  std::filesystem::create_directories(dir_.path() + "/.hidden/1");
  std::filesystem::create_directories(dir_.path() + "/bad name/1");
  std::filesystem::create_directories(dir_.path() + "/good/latest");  // not a version
  std::filesystem::create_directories(dir_.path() + "/good/007");     // leading zero
  Start();
  EXPECT_EQ(registry_->snapshot()->models.size(), 1u);
  EXPECT_THAT(Model("good")->available_versions, ElementsAre(1));
  for (const char* name : {"../good", "good/1", ".hidden", "bad name", ""}) {
    EXPECT_EQ(registry_->Resolve(name, 0).status().code(), absl::StatusCode::kInvalidArgument)
        << name;
  }
  EXPECT_EQ(registry_->Resolve("nope", 0).status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(registry_->Resolve("good", -1).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(ModelRegistryTest, AddsReplacesAndRemovesWhileRequestsHoldTheOldVersion) {
  Write("a", 1, testing::SphereIndexBytes());
  Start();
  auto held = registry_->Resolve("a", 0);
  ASSERT_TRUE(held.ok());
  const query::InputQueries& old_queries = held->version->queries();

  Write("a", 2, OtherSphereBytes());
  Write("b", 1, testing::TorusIndexBytes());
  registry_->RescanNow();
  EXPECT_EQ(registry_->Resolve("a", 0)->version->version(), 2);
  EXPECT_EQ(Model("b")->state, LoadState::kServing);
  // The request that resolved version 1 still runs on it.
  EXPECT_EQ(held->version->version(), 1);
  const std::vector<mesh::SurfacePoint> input = {{0, {1, 0, 0}}, {10, {0, 1, 0}}};
  query::EnginePoints points;
  ASSERT_TRUE(old_queries.Read(input, query::Named("p"), &points).ok());
  EXPECT_TRUE(old_queries.Distance(points, 0, points, 1).ok());

  testing::RemoveModel(dir_.path(), "a");
  registry_->RescanNow();
  EXPECT_EQ(registry_->Resolve("a", 0).status().code(), absl::StatusCode::kNotFound);
  EXPECT_TRUE(old_queries.Distance(points, 0, points, 1).ok());  // still mapped while held
}

TEST_F(ModelRegistryTest, ReloadsAVersionWhoseFileChanged) {
  Write("a", 1, testing::SphereIndexBytes());
  Start();
  EXPECT_EQ(registry_->Resolve("a", 0)->version->index().num_samples(), 40);
  Write("a", 1, OtherSphereBytes());  // same version, new file (renamed into place)
  registry_->RescanNow();
  EXPECT_EQ(registry_->Resolve("a", 0)->version->index().num_samples(), 30);
}

// A served file changed in place (same inode) no longer holds what was
// validated: it stops being served, and is served again once it validates.
TEST_F(ModelRegistryTest, AFileModifiedInPlaceStopsBeingServed) {
  Write("a", 1, testing::SphereIndexBytes());
  Write("b", 1, testing::SphereIndexBytes());
  Start();
  ASSERT_TRUE(registry_->Resolve("a", 0).ok());
  const std::string path = dir_.path() + "/a/1/index.gdx";
  {
    // Overwrite bytes in the middle without truncating or renaming, and move
    // the mtime on so the change is seen even within one clock tick.
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(testing::SphereIndexBytes().size() / 2));
    f << std::string(64, '\x5a');
  }
  std::filesystem::last_write_time(
      path, std::filesystem::last_write_time(path) + std::chrono::seconds(2));
  registry_->RescanNow();
  auto resolved = registry_->Resolve("a", 0);
  EXPECT_EQ(resolved.status().code(), absl::StatusCode::kUnavailable) << resolved.status();
  EXPECT_EQ(Model("a")->state, LoadState::kFailed);
  EXPECT_THAT(Model("a")->reason, HasSubstr("checksum"));
  EXPECT_TRUE(registry_->Resolve("b", 0).ok());  // the others serve on

  // Rewritten in place with valid contents: validated again, served again.
  {
    std::ofstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f << testing::SphereIndexBytes();
  }
  std::filesystem::last_write_time(
      path, std::filesystem::last_write_time(path) + std::chrono::seconds(2));
  registry_->RescanNow();
  EXPECT_TRUE(registry_->Resolve("a", 0).ok());
  EXPECT_EQ(Model("a")->state, LoadState::kServing);
}

TEST_F(ModelRegistryTest, BrokenNewVersionKeepsThePreviousServing) {
  Write("a", 1, testing::SphereIndexBytes());
  Start();
  const std::string& good = OtherSphereBytes();
  Write("a", 2, good.substr(0, good.size() / 2));  // truncated
  registry_->RescanNow();
  auto m = Model("a");
  EXPECT_EQ(m->state, LoadState::kFailed);
  EXPECT_THAT(m->reason, HasSubstr("version 2"));
  EXPECT_THAT(m->reason, HasSubstr("DATA_LOSS"));
  EXPECT_EQ(registry_->Resolve("a", 0)->version->version(), 1);

  // Not retried while the file is unchanged; fixed by a new file.
  registry_->RescanNow();
  EXPECT_EQ(Model("a")->state, LoadState::kFailed);
  Write("a", 2, good);
  registry_->RescanNow();
  EXPECT_EQ(Model("a")->state, LoadState::kServing);
  EXPECT_EQ(registry_->Resolve("a", 0)->version->version(), 2);
}

TEST_F(ModelRegistryTest, BrokenNewestAtStartServesTheNewestGoodOne) {
  Write("a", 1, testing::SphereIndexBytes());
  Write("a", 2, "not an index at all, just some bytes that are long enough to be checked");
  Start();
  auto m = Model("a");
  EXPECT_EQ(m->state, LoadState::kFailed);
  EXPECT_THAT(m->reason, HasSubstr("not a geodex index"));
  EXPECT_EQ(registry_->Resolve("a", 0)->version->version(), 1);
}

TEST_F(ModelRegistryTest, OnlyVersionBrokenIsUnavailableWithTheReason) {
  Write("a", 1, "garbage garbage garbage garbage garbage garbage garbage garbage garbage");
  Write("ok", 1, testing::SphereIndexBytes());
  Start();
  auto resolved = registry_->Resolve("a", 0);
  EXPECT_EQ(resolved.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(resolved.status().message()), HasSubstr("failed to load"));
  EXPECT_TRUE(registry_->Resolve("ok", 0).ok());
}

TEST_F(ModelRegistryTest, BadConfigFailsButKeepsServing) {
  Write("a", 1, testing::SphereIndexBytes());
  Start();
  testing::WriteModelConfig(dir_.path(), "a", "keep_versions: banana\n");
  registry_->RescanNow();
  auto m = Model("a");
  EXPECT_EQ(m->state, LoadState::kFailed);
  EXPECT_THAT(m->reason, HasSubstr("config.textproto:1:"));
  EXPECT_TRUE(registry_->Resolve("a", 0).ok());
  testing::WriteModelConfig(dir_.path(), "a", "limits { max_pairs_per_message: 5 }\n");
  registry_->RescanNow();
  EXPECT_EQ(Model("a")->state, LoadState::kServing);
  EXPECT_EQ(Model("a")->config.limits().max_pairs_per_message(), 5);
}

TEST_F(ModelRegistryTest, LoadingIsUnavailable) {
  Write("a", 1, testing::SphereIndexBytes());
  std::latch entered(1), release(1);
  RegistryOptions options;
  options.root = dir_.path();
  options.poll_interval = absl::ZeroDuration();
  options.before_load = [&](const std::string&) {
    entered.count_down();
    release.wait();
  };
  auto registry = ModelRegistry::Create(options);
  ASSERT_TRUE(registry.ok());
  registry_ = *std::move(registry);
  registry_->Start();
  entered.wait();
  auto m = Model("a");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->state, LoadState::kLoading);
  EXPECT_EQ(m->loading_version, 1);
  EXPECT_EQ(registry_->Resolve("a", 0).status().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(registry_->Resolve("a", 1).status().code(), absl::StatusCode::kUnavailable);
  release.count_down();
  registry_->RescanNow();
  EXPECT_TRUE(registry_->Resolve("a", 0).ok());
}

TEST_F(ModelRegistryTest, PollingPicksUpChanges) {
  RegistryOptions options;
  options.poll_interval = absl::Milliseconds(20);
  Start(options);
  Write("late", 1, testing::SphereIndexBytes());
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!registry_->Resolve("late", 0).ok() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(registry_->Resolve("late", 0).ok());
}

TEST_F(ModelRegistryTest, ListenerSeesEveryPublishedState) {
  Write("a", 1, testing::SphereIndexBytes());
  std::vector<LoadState> states;
  RegistryOptions options;
  options.root = dir_.path();
  options.poll_interval = absl::ZeroDuration();
  auto registry = ModelRegistry::Create(options);
  ASSERT_TRUE(registry.ok());
  registry_ = *std::move(registry);
  registry_->SetListener([&](const RegistrySnapshot&, const RegistrySnapshot& after) {
    auto it = after.models.find("a");
    if (it != after.models.end()) states.push_back(it->second->state);
  });
  registry_->Start();
  registry_->RescanNow();
  ASSERT_GE(states.size(), 2u);
  EXPECT_EQ(states.front(), LoadState::kLoading);
  EXPECT_EQ(states.back(), LoadState::kServing);
}

TEST_F(ModelRegistryTest, OneEngineAnswersEveryNearPairMode) {
  Write("a", 1, testing::SphereIndexBytes());
  Start();
  auto resolved = registry_->Resolve("a", 0);
  ASSERT_TRUE(resolved.ok());
  const query::InputQueries& queries = resolved->version->queries();
  // A point and another of the same face: a near pair, answered by each mode.
  const std::vector<mesh::SurfacePoint> input = {{0, {0.6, 0.2, 0.2}}, {0, {0.1, 0.1, 0.8}}};
  query::EnginePoints points;
  ASSERT_TRUE(queries.Read(input, query::Named("p"), &points).ok());
  for (auto mode : {query::NearPairs::kPath, query::NearPairs::kUnfold, query::NearPairs::kExact}) {
    EXPECT_TRUE(queries.Distance(points, 0, points, 1, {.near_pairs = mode}).ok());
  }
}

}  // namespace
}  // namespace geodex::server
