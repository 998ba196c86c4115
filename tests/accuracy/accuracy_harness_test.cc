#include "tests/accuracy/accuracy_harness.h"

#include <filesystem>
#include <string>
#include <vector>

#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::accuracy {
namespace {

using ::testing::HasSubstr;

HarnessFlags Parse(const std::string& line) {
  AccuracyCommandLine cli;
  cli.app().parse(line, /*program_name_included=*/false);
  return cli.flags();
}

TEST(AccuracyCommandLineTest, Defaults) {
  const HarnessFlags flags = Parse("a.obj builtin:torus");
  EXPECT_EQ(flags.meshes, (std::vector<std::string>{"a.obj", "builtin:torus"}));
  EXPECT_EQ(flags.samples, (std::vector<int32_t>{1000}));
  EXPECT_EQ(flags.modes, (std::vector<std::string>{"unfold", "default", "bounds", "tol0.005"}));
  EXPECT_EQ(flags.index_dir, "");
  EXPECT_EQ(flags.threads, 0);
  EXPECT_FALSE(flags.no_split);
  EXPECT_FALSE(flags.error_driven);
}

TEST(AccuracyCommandLineTest, ListsAreCommaSeparated) {
  const HarnessFlags flags = Parse(
      "m.obj --samples 250,500 --modes trace,nowalk --sources 6 --points 20 --per-bin 4 "
      "--seed 3 --index-dir d --threads 2 --no-split --error-driven");
  EXPECT_EQ(flags.samples, (std::vector<int32_t>{250, 500}));
  EXPECT_EQ(flags.modes, (std::vector<std::string>{"trace", "nowalk"}));
  EXPECT_EQ(flags.pairs.num_sources, 6);
  EXPECT_EQ(flags.pairs.uniform_points, 20);
  EXPECT_EQ(flags.pairs.per_bin_points, 4);
  EXPECT_EQ(flags.pairs.seed, 3u);
  EXPECT_EQ(flags.index_dir, "d");
  EXPECT_EQ(flags.threads, 2);
  EXPECT_TRUE(flags.no_split);
  EXPECT_TRUE(flags.error_driven);
  EXPECT_THROW(Parse("--samples 5"), CLI::RequiredError);
}

TEST(AccuracyHarnessTest, AnswerModes) {
  absl::StatusOr<AnswerMode> mode = ParseAnswerMode("unfold");
  ASSERT_TRUE(mode.ok());
  EXPECT_EQ(mode->options.near_pairs, query::NearPairs::kUnfold);
  EXPECT_FALSE(mode->bounds);
  mode = ParseAnswerMode("exact");
  EXPECT_EQ(mode->options.near_pairs, query::NearPairs::kExact);
  mode = ParseAnswerMode("bounds");
  EXPECT_TRUE(mode->bounds);
  EXPECT_EQ(mode->options.near_pairs, query::DistanceOptions{}.near_pairs);
  mode = ParseAnswerMode("tol0.01");
  EXPECT_TRUE(mode->bounds);
  EXPECT_EQ(mode->options.tolerance, 0.01);
  mode = ParseAnswerMode("trace");
  EXPECT_TRUE(mode->trace);
  EXPECT_FALSE(mode->nowalk);
  mode = ParseAnswerMode("nowalk");
  EXPECT_TRUE(mode->nowalk);
  EXPECT_FALSE(mode->trace);
  mode = ParseAnswerMode("default");
  EXPECT_FALSE(mode->bounds || mode->trace || mode->nowalk);

  mode = ParseAnswerMode("fast");
  EXPECT_EQ(mode.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(mode.status().message(), "unknown mode fast");
}

TEST(AccuracyHarnessTest, CachedIndexPath) {
  HarnessFlags flags;
  EXPECT_EQ(CachedIndexPath(flags, "bunny", 500, ""), "/tmp/bunny-m500.gdx");
  flags.index_dir = "idx";
  flags.no_split = true;
  EXPECT_EQ(CachedIndexPath(flags, "bunny", 500, "-placed"), "idx/bunny-m500-noref-placed.gdx");
}

TEST(AccuracyHarnessTest, BuiltinMeshes) {
  for (const char* name :
       {"builtin:sphere", "builtin:torus", "builtin:folded", "builtin:cylinder"}) {
    const absl::StatusOr<mesh::Mesh> m = LoadHarnessMesh(name);
    ASSERT_TRUE(m.ok()) << name << ": " << m.status();
    EXPECT_GT(m->num_faces(), 1000) << name;
  }
  EXPECT_FALSE(LoadHarnessMesh("builtin:nothing").ok());  // read as a file name
}

TEST(AccuracyHarnessTest, IndexIsCachedAndCalibrated) {
  const auto dir = std::filesystem::temp_directory_path() / "geodex_accuracy_harness_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  HarnessFlags flags;
  flags.index_dir = dir.string();
  flags.threads = 2;
  const mesh::Mesh m = mesh::gen::Sphere(2, 1.0);
  absl::StatusOr<std::shared_ptr<const index::Index>> index = IndexFor(flags, m, "s", 30, "", {});
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_NE((*index)->accuracy(), nullptr);
  const std::string file = CachedIndexPath(flags, "s", 30, "");
  ASSERT_TRUE(std::filesystem::exists(file));
  const auto written = std::filesystem::last_write_time(file);
  index = IndexFor(flags, m, "s", 30, "", {});  // reused, not built again
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_EQ(std::filesystem::last_write_time(file), written);

  // An unknown mode fails after the modes before it.
  flags.modes = {"unfold", "fast"};
  const auto pairs = validation::DrawPairs(
      m, (*index)->num_samples(),
      {.num_sources = 2, .uniform_points = 10, .per_bin_points = 2, .seed = 1});
  const absl::Status status = MeasureModes(flags, "s", pairs, *index);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("unknown mode fast"));
}

}  // namespace
}  // namespace geodex::accuracy
