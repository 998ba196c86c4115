#include "core/build/build_pipeline.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/common/file_util.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::builder {
namespace {

using ::testing::ContainsRegex;
using ::testing::HasSubstr;
using ::testing::Not;

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

// The numbers of "label 1.5s" / "label 2m05s" (FormatSeconds), in seconds.
double ParseSeconds(absl::string_view text) {
  int minutes = 0;
  double seconds = 0;
  const std::string s(text);
  if (std::sscanf(s.c_str(), "%dm%lfs", &minutes, &seconds) == 2) return 60 * minutes + seconds;
  return std::sscanf(s.c_str(), "%lfs", &seconds) == 1 ? seconds : -1;
}

// The report of a default build (no sample count: to the default target)
// gives one verdict: the target line and the tables agree, lengths are in
// L1000 but where the walked / O(1) split is explained in the index's own
// L, m is said to be the target's choice, and the time line adds up to the
// build's wall time.
TEST(BuildPipelineTest, DefaultBuildsReportIsOneVerdictInOneUnit) {
  const std::string dir = TempDir("default_report");
  const std::string sphere = dir + "/sphere.obj";
  ASSERT_TRUE(mesh::WriteObj(mesh::gen::Sphere(3, 1.0), sphere).ok());
  PipelineOptions options = WithSampleDefaults(Fixed(1000), /*samples_asked=*/false);
  EXPECT_EQ(options.target_error, 0.005);
  const auto start = std::chrono::steady_clock::now();
  absl::StatusOr<BuildReport> built = BuildIndexFile(sphere, dir + "/x.gdx", options);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(built.ok()) << built.status();
  const std::string& text = built->text;
  EXPECT_THAT(text, HasSubstr("error target  0.500% met in 1 round"));
  EXPECT_THAT(text, HasSubstr("(chosen by the target; rounds m = "));
  EXPECT_THAT(text, Not(HasSubstr("requested")));
  // Met: no check, row or column says otherwise, and the bins by the
  // index's own L, which the target does not judge, carry no limit.
  EXPECT_THAT(text, Not(HasSubstr("  over")));
  EXPECT_THAT(text, Not(HasSubstr("over the limit")));
  EXPECT_THAT(text, Not(HasSubstr("limit  ")));
  EXPECT_THAT(text, Not(HasSubstr("3L-10L")));
  EXPECT_THAT(text, Not(HasSubstr("--")));
  EXPECT_THAT(text, HasSubstr("judged by the target: measured (95% upper limit / limit)"));
  for (const char* check : {"uniform RMS", "vertex >=8 L1000 p99", "interior >=8 L1000 p99"}) {
    EXPECT_THAT(text, HasSubstr(absl::StrCat("\n                  ", check))) << check;
  }
  // L appears once, where it explains the split, and says what it is.
  EXPECT_THAT(text, ContainsRegex("where L = [0-9.]+ is this index's own sample spacing"));
  size_t own_l = 0;
  for (size_t at = text.find(" L = "); at != std::string::npos; at = text.find(" L = ", at + 1)) {
    ++own_l;
  }
  EXPECT_EQ(own_l, 1u) << text;

  // "time          12.3s in all: sampling ..., the rest (...) 0.4s".
  const size_t line = text.find("\n  time          ");
  ASSERT_NE(line, std::string::npos) << text;
  const std::string time_line = text.substr(line + 17, text.find('\n', line + 1) - line - 17);
  const std::vector<std::string> words =
      absl::StrSplit(time_line, absl::ByAnyChar(" ,:"), absl::SkipEmpty());
  ASSERT_GE(words.size(), 3u) << time_line;
  const double total = ParseSeconds(words[0]);
  double parts = 0;
  int counted = 0;
  for (size_t i = 3; i < words.size(); ++i) {
    const double seconds = ParseSeconds(words[i]);
    if (seconds >= 0 && absl::EndsWith(words[i], "s")) {
      parts += seconds;
      ++counted;
    }
  }
  EXPECT_THAT(time_line, HasSubstr("validation "));
  EXPECT_EQ(counted, 6) << time_line;  // five phases and the rest
  EXPECT_NEAR(parts, total, 0.05 * counted + 0.05) << time_line;
  EXPECT_LE(total, wall + 0.05) << time_line;
  EXPECT_GE(total, wall - 0.3) << time_line;
}

}  // namespace
}  // namespace geodex::builder
