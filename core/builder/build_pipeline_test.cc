#include "core/builder/build_pipeline.h"

#include <filesystem>

#include "core/common/file_util.h"
#include "core/index/index.h"
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
  absl::StatusOr<BuildReport> one = BuildIndexFile("builtin:sphere", dir + "/one.gdx", Fixed(40));
  ASSERT_TRUE(one.ok()) << one.status();
  EXPECT_THAT(one->text, testing::HasSubstr("geodex-build: wrote " + dir + "/one.gdx"));
  EXPECT_THAT(one->text, testing::HasSubstr("  accuracy "));
  EXPECT_EQ(one->num_samples, 40);
  EXPECT_GT(one->index_bytes, 0u);

  PipelineOptions sharded = Fixed(40);
  sharded.build.threads = 1;
  ASSERT_TRUE(PlanBuild("builtin:sphere", dir + "/wd", sharded).ok());
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
  ASSERT_TRUE(BuildIndexFile("builtin:sphere", dir + "/plain.gdx", plain).ok());
  EXPECT_NE(FileBytes(dir + "/plain.gdx"), FileBytes(dir + "/one.gdx"));
  ASSERT_TRUE(
      CalibrateIndexFile("builtin:sphere", dir + "/plain.gdx", dir + "/calibrated.gdx", plain)
          .ok());
  EXPECT_EQ(FileBytes(dir + "/calibrated.gdx"), FileBytes(dir + "/one.gdx"));

  // An index is calibrated only against the mesh it was built from.
  EXPECT_EQ(CalibrateIndexFile("builtin:torus", dir + "/plain.gdx", dir + "/x.gdx", plain)
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
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
