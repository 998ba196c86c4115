#include "core/builder/build_pipeline.h"

#include <filesystem>

#include "core/common/file_util.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::builder {
namespace {

std::string TempDir(const std::string& name) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("geodex_build_pipeline_test_" + name)).string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

PipelineOptions Fixed(int32_t samples) {
  PipelineOptions options;
  options.build.num_samples = samples;
  options.build.threads = 2;
  return options;
}

std::string FileBytes(const std::string& path) {
  absl::StatusOr<std::string> bytes = ReadWholeFile(path);
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  return bytes.ok() ? *bytes : std::string();
}

TEST(ParseShardTest, TakesIOverNAndRefusesTheRest) {
  EXPECT_EQ(ParseShard("0/1").value(), std::make_pair(0, 1));
  EXPECT_EQ(ParseShard("2/3").value(), std::make_pair(2, 3));
  for (const char* bad : {"3/3", "-1/3", "1/0", "1", "1/3x", "a/b", ""}) {
    EXPECT_EQ(ParseShard(bad).status().code(), absl::StatusCode::kInvalidArgument) << bad;
  }
}

TEST(LoadBuildInputTest, BuiltinsAndErrors) {
  absl::StatusOr<mesh::RepairedMesh> torus = LoadBuildInput("builtin:torus", {});
  ASSERT_TRUE(torus.ok()) << torus.status();
  EXPECT_EQ(torus->mesh.num_vertices(), 96 * 48);
  EXPECT_EQ(LoadBuildInput("builtin:teapot", {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(LoadBuildInput("/nonexistent/mesh.obj", {}).status().code(),
            absl::StatusCode::kNotFound);
}

// One process, the plan / rows / merge steps with three shards, and a build
// without calibration calibrated afterwards all give the same file.
TEST(BuildPipelineTest, EveryRouteGivesTheSameIndex) {
  const std::string dir = TempDir("routes");
  // A small sphere: what is compared is the routes, not the mesh.
  const std::string sphere = dir + "/sphere.obj";
  ASSERT_TRUE(mesh::WriteObj(mesh::gen::Sphere(3, 1.0), sphere).ok());
  absl::StatusOr<BuildReport> one = BuildIndexFile(sphere, dir + "/one.gdx", Fixed(40));
  ASSERT_TRUE(one.ok()) << one.status();
  EXPECT_THAT(one->text, testing::HasSubstr("geodex-build: wrote " + dir + "/one.gdx"));
  EXPECT_THAT(one->text, testing::HasSubstr("  accuracy "));
  EXPECT_EQ(one->num_samples, 40);
  EXPECT_GT(one->index_bytes, 0u);

  PipelineOptions sharded = Fixed(40);
  sharded.build.threads = 1;
  ASSERT_TRUE(PlanBuild(sphere, dir + "/wd", sharded).ok());
  for (const char* shard : {"0/3", "1/3", "2/3"}) {
    absl::StatusOr<BuildReport> rows = ComputeShardRows(dir + "/wd", shard, sharded);
    ASSERT_TRUE(rows.ok()) << rows.status();
  }
  EXPECT_EQ(ComputeShardRows(dir + "/wd", "3/3", sharded).status().code(),
            absl::StatusCode::kInvalidArgument);
  ASSERT_TRUE(MergeBuild(dir + "/wd", dir + "/merged.gdx", sharded).ok());
  EXPECT_EQ(FileBytes(dir + "/merged.gdx"), FileBytes(dir + "/one.gdx"));

  PipelineOptions plain = Fixed(40);
  plain.calibrate = false;
  ASSERT_TRUE(BuildIndexFile(sphere, dir + "/plain.gdx", plain).ok());
  EXPECT_NE(FileBytes(dir + "/plain.gdx"), FileBytes(dir + "/one.gdx"));
  ASSERT_TRUE(
      CalibrateIndexFile(sphere, dir + "/plain.gdx", dir + "/calibrated.gdx", plain)
          .ok());
  EXPECT_EQ(FileBytes(dir + "/calibrated.gdx"), FileBytes(dir + "/one.gdx"));

  // An index is calibrated only against the mesh it was built from.
  EXPECT_EQ(CalibrateIndexFile("builtin:torus", dir + "/plain.gdx", dir + "/x.gdx", plain)
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
  std::filesystem::remove_all(dir);
}

// A target-error build in one process and the same build distributed
// (plan, then rows shards and merge until merge writes the index) give the
// same index, after the same rounds.
TEST(BuildPipelineTest, DistributedTargetErrorBuildIsTheOneProcessBuild) {
  const std::string dir = TempDir("target");
  const std::string mesh_path = dir + "/sphere.obj";
  ASSERT_TRUE(mesh::WriteObj(mesh::gen::Sphere(3, 1.0), mesh_path).ok());
  PipelineOptions options;
  options.build.num_samples = 60;
  options.build.threads = 2;
  options.target_error = 0.011;
  std::vector<std::string> one_log, distributed_log;
  options.log = [&](const std::string& line) { one_log.push_back(line); };
  absl::StatusOr<BuildReport> one = BuildIndexFile(mesh_path, dir + "/one.gdx", options);
  ASSERT_TRUE(one.ok()) << one.status();
  EXPECT_FALSE(one->another_round);
  ASSERT_GE(one_log.size(), 2u);  // at least two rounds

  options.build.threads = 1;
  options.log = [&](const std::string& line) { distributed_log.push_back(line); };
  ASSERT_TRUE(PlanBuild(mesh_path, dir + "/wd", options).ok());
  int merges = 0;
  for (bool more = true; more && merges < 10; ++merges) {
    for (const char* shard : {"0/2", "1/2"}) {
      absl::StatusOr<BuildReport> rows = ComputeShardRows(dir + "/wd", shard, options);
      ASSERT_TRUE(rows.ok()) << rows.status();
    }
    absl::StatusOr<BuildReport> merged = MergeBuild(dir + "/wd", dir + "/merged.gdx", options);
    ASSERT_TRUE(merged.ok()) << merged.status();
    more = merged->another_round;
    EXPECT_EQ(std::filesystem::exists(dir + "/merged.gdx"), !more);
  }
  EXPECT_EQ(merges, static_cast<int>(one_log.size()));
  EXPECT_EQ(FileBytes(dir + "/merged.gdx"), FileBytes(dir + "/one.gdx"));
  // The round lines agree but for the one process's timings.
  ASSERT_EQ(distributed_log.size(), one_log.size());
  for (size_t k = 0; k < one_log.size(); ++k) {
    EXPECT_EQ(one_log[k].substr(0, distributed_log[k].size()), distributed_log[k]);
  }
  // A fixed-m plan in the same work directory is a fixed-m build again.
  ASSERT_TRUE(PlanBuild(mesh_path, dir + "/wd", Fixed(40)).ok());
  ASSERT_TRUE(ComputeShardRows(dir + "/wd", "0/1", Fixed(40)).ok());
  absl::StatusOr<BuildReport> fixed = MergeBuild(dir + "/wd", dir + "/fixed.gdx", Fixed(40));
  ASSERT_TRUE(fixed.ok()) << fixed.status();
  EXPECT_EQ(fixed->num_samples, 40);
  std::filesystem::remove_all(dir);
}

TEST(BuildPipelineTest, EdgesObjIsWritten) {
  const std::string dir = TempDir("edges");
  PipelineOptions options = Fixed(30);
  options.calibrate = false;
  options.edges_obj = dir + "/edges.obj";
  absl::StatusOr<BuildReport> report = BuildIndexFile("builtin:sphere", dir + "/x.gdx", options);
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_THAT(report->text, testing::HasSubstr("geodesic edges to " + options.edges_obj));
  EXPECT_THAT(FileBytes(options.edges_obj), testing::HasSubstr("\nl "));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace geodex::builder
