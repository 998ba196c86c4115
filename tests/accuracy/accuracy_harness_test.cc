#include "tests/accuracy/accuracy_harness.h"

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/mesh/generators.h"
#include "tests/accuracy/accuracy.h"
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

TEST(AccuracyCommandLineTest, AnIndexFileAndATarget) {
  const HarnessFlags flags = Parse("m.obj --index m.gdx --target-error 0.005");
  EXPECT_EQ(flags.index_file, "m.gdx");
  EXPECT_EQ(flags.target_error, 0.005);
  EXPECT_EQ(Parse("m.obj").target_error, 0);
}

TEST(AccuracyHarnessTest, AnIndexFileNeedsOneMesh) {
  HarnessFlags flags = Parse("a.obj b.obj --index a.gdx");
  const absl::Status status = RunHarness(flags);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("one mesh"));
}

// Pairs at known distances, answered with known errors: the fixed bins and
// the target's checks count what they should.
TEST(AccuracyHarnessTest, FixedBinsAndTheTargetChecks) {
  const double unit = 2.0;  // L1000
  std::vector<ExactPair> pairs;
  auto add = [&](double exact, bool vertices, bool uniform) {
    ExactPair pair;
    pair.exact = exact;
    pair.vertices = vertices;
    pair.uniform = uniform;
    pair.q.face = static_cast<int32_t>(pairs.size());  // the answer below finds the pair by it
    pairs.push_back(pair);
  };
  for (int i = 0; i < 100; ++i) add(0.5, false, true);   // 0.25 L1000: bin 0-0.5
  for (int i = 0; i < 100; ++i) add(20.0, true, true);   // 10 L1000: 8-16, far
  for (int i = 0; i < 100; ++i) add(40.0, false, true);  // 20 L1000: >=16, far
  // Relative error 1% below 8 L1000 and 0.5% beyond: RMS over the uniform
  // interior pairs (bins 0-0.5 and >=16) is sqrt((1e-4 + 0.25e-4) / 2).
  const AnswerFn answer = [&](const mesh::SurfacePoint&, const mesh::SurfacePoint& q) {
    const double exact = pairs[q.face].exact;
    return Answer{exact * (exact >= 8 * unit ? 1.005 : 1.01)};
  };
  const ModeReport report = Evaluate(pairs, answer, unit);
  EXPECT_EQ(report.fixed_interior[0].error.count, 100);
  EXPECT_EQ(report.fixed_vertex[5].error.count, 100);
  EXPECT_EQ(report.fixed_interior[6].error.count, 100);
  EXPECT_EQ(report.far_vertex.error.count, 100);
  EXPECT_EQ(report.far_interior.error.count, 100);
  EXPECT_NEAR(report.far_interior.error.p99, 0.005, 1e-12);
  EXPECT_NEAR(report.uniform.rms, std::sqrt((1e-4 + 0.25e-4) / 2), 1e-12);

  std::string rows = MarkdownFixedRows("x", report, 0.01);
  EXPECT_THAT(rows, HasSubstr("| x | interior | 0-0.5 L1000 | 100 |"));
  EXPECT_THAT(rows, HasSubstr("**target met**"));
  rows = MarkdownFixedRows("x", report, 0.004);  // RMS 0.79% > 0.4%; p99 0.5% <= 1.6%
  EXPECT_THAT(rows, HasSubstr("**target NOT met**"));
  EXPECT_THAT(rows, HasSubstr("uniform RMS 0.791% (<= 0.400%) NOT met"));
  rows = MarkdownFixedRows("x", report, 0.001);  // p99 0.5% > 0.4% too
  EXPECT_THAT(rows, HasSubstr("vertex 0.500% NOT met"));

  // Without a unit the fixed bins stay empty.
  EXPECT_EQ(Evaluate(pairs, answer).far_vertex.error.count, 0);
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
  mode = ParseAnswerMode("below8");
  EXPECT_EQ(mode->options.refine_below_l1000, 8);
  EXPECT_TRUE(mode->bounds);
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
