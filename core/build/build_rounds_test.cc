#include "core/build/build_rounds.h"

#include <filesystem>

#include "core/builder/workdir.h"
#include "core/mesh/generators.h"
#include "gtest/gtest.h"

namespace geodex::builder {
namespace {

using validation::TargetFigures;

RoundsOptions Options(int32_t first, double target) {
  RoundsOptions options;
  options.build.num_samples = first;
  options.build.threads = 2;
  options.target = target;
  options.validation_sources = 64;
  return options;
}

// 60 samples on a sphere are not enough for 1.1%: the build grows them,
// judged by upper confidence limits (never below the measured figures), and
// stops where the last round meets every check.
TEST(BuildRoundsTest, GrowsTheSamplesUntilTheTargetIsMet) {
  const mesh::Mesh m = mesh::gen::Sphere(3, 1.0);
  std::vector<std::string> lines;
  absl::StatusOr<TargetBuild> result =
      BuildToTarget(m, {}, Options(60, 0.011), [&](const std::string& l) { lines.push_back(l); });
  ASSERT_TRUE(result.ok()) << result.status();
  ASSERT_TRUE(result->last.reached);
  ASSERT_GE(result->rounds.size(), 2u);
  EXPECT_EQ(lines.size(), result->rounds.size());
  EXPECT_FALSE(validation::TargetMet(result->rounds.front(), 0.011));
  EXPECT_TRUE(validation::TargetMet(result->rounds.back(), 0.011));
  for (const TargetFigures& r : result->rounds) {
    for (int c = 0; c < validation::kNumTargetChecks; ++c) EXPECT_GE(r.upper[c], r.measured[c]);
  }
  for (size_t k = 1; k < result->rounds.size(); ++k) {
    EXPECT_GT(result->rounds[k].samples, result->rounds[k - 1].samples);
  }
  ASSERT_EQ(result->data.accuracy.size(), 1u);
  EXPECT_EQ(result->data.samples.size(), static_cast<size_t>(result->rounds.back().samples));
  EXPECT_EQ(result->plan.samples, result->data.samples);
  EXPECT_NE(result->data.report.find("target_error_reached = yes\n"), std::string::npos);
  EXPECT_NE(result->data.report.find("target_error_round_2 = m = "), std::string::npos);
}

TEST(BuildRoundsTest, StopsAtTheCapAndSaysSo) {
  // A long thin torus: at 60 samples most pairs are far apart in the
  // index's own L, answered in O(1), which no m meets 1e-6 with. (On a
  // small sphere every pair would be near and refined exactly.)
  const mesh::Mesh m = mesh::gen::Torus(64, 12, 4.0, 0.5);
  RoundsOptions options = Options(60, 1e-6);
  options.max_samples = 60;
  absl::StatusOr<TargetBuild> result = BuildToTarget(m, {}, options, nullptr);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_FALSE(result->last.reached);
  EXPECT_EQ(result->rounds.size(), 1u);  // at the cap from the first round
  EXPECT_NE(result->data.report.find("target_error_reached = no (the cap of "), std::string::npos)
      << result->data.report;
  options.target = -1;
  EXPECT_EQ(BuildToTarget(m, {}, options, nullptr).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// The next round carries the samples and rows of the one before.
TEST(BuildRoundsTest, TheNextRoundCarriesTheSamplesAndRows) {
  const mesh::Mesh coarse = mesh::gen::Cube(3, 2.0);  // refined again for more samples
  const RoundsOptions options = Options(40, 0.01);
  absl::StatusOr<RoundPlan> first = PlanFirstRound(coarse, {}, options);
  ASSERT_TRUE(first.ok()) << first.status();
  std::vector<int32_t> all(first->plan.num_samples());
  for (int32_t a = 0; a < first->plan.num_samples(); ++a) all[a] = a;
  absl::StatusOr<std::vector<SampleRow>> rows =
      ComputeRows(first->prepared.mesh, first->plan, all, options.build);
  ASSERT_TRUE(rows.ok());
  absl::StatusOr<RoundPlan> next = PlanNextRound(coarse, {}, *first, *rows, 100, options);
  ASSERT_TRUE(next.ok()) << next.status();
  EXPECT_GT(next->prepared.mesh.num_vertices(), first->prepared.mesh.num_vertices());
  ASSERT_EQ(next->carried.size(), first->plan.samples.size());
  for (size_t a = 0; a < first->plan.samples.size(); ++a) {
    EXPECT_EQ(next->plan.samples[a], first->plan.samples[a]);
    EXPECT_EQ(next->carried[a].to_samples, (*rows)[a].to_samples);
    EXPECT_TRUE(next->carried[a].to_cell_vertices.empty());
  }
  EXPECT_GE(next->plan.num_samples(), 100);
}

TEST(BuildRoundsTest, DecideNext) {
  TargetFigures met;
  met.samples = 500;
  for (int c = 0; c < validation::kNumTargetChecks; ++c) met.pairs[c] = 10;
  constexpr int64_t kSmall = 1 << 20;  // an index of 1 MiB
  constexpr int64_t kBudget = validation::kMaxIndexBytes;
  EXPECT_TRUE(DecideNext({met}, 500, 8000, 0.005, kSmall, kBudget).reached);
  TargetFigures missed = met;
  missed.upper[0] = 0.01;
  NextStep next = DecideNext({missed}, 500, 8000, 0.005, kSmall, kBudget);
  EXPECT_FALSE(next.done);
  EXPECT_GT(next.num_samples, 500);
  next = DecideNext({missed}, 8000, 8000, 0.005, kSmall, kBudget);
  EXPECT_TRUE(next.done);
  EXPECT_FALSE(next.reached);
  EXPECT_EQ(next.stop, "the cap of 8000 samples");
  // An index already at the size budget stops m where it is.
  missed.samples = 5000;
  next = DecideNext({missed}, 5000, 8000, 0.005, kBudget, kBudget);
  EXPECT_TRUE(next.done);
  EXPECT_FALSE(next.reached);
  EXPECT_EQ(next.stop, "the index size budget of 32 MiB");
  // Below it, m grows at most to what fits, with 3% of the budget spare.
  missed.samples = 3000;
  const int64_t bytes = int64_t{3000} * 2999 + 3000 * 200;
  next = DecideNext({missed}, 3000, 8000, 0.005, bytes, kBudget);
  EXPECT_FALSE(next.done);
  EXPECT_EQ(next.num_samples, validation::SamplesWithinBytes(kBudget * 97 / 100, 3000, bytes));
  // Room for less than the least growth of a round (1.2x): stop there, and
  // say which budget.
  missed.samples = 4800;
  next = DecideNext({missed}, 4800, 8000, 0.005, int64_t{4800} * 4799, 20 << 20);
  EXPECT_TRUE(next.done);
  EXPECT_EQ(next.stop, "the index size budget of 20 MiB");
  EXPECT_EQ(next.keep, 0);
}

// A round no closer to the target than the closest before it ends the build,
// which keeps that closest round.
TEST(BuildRoundsTest, ARoundThatComesNoCloserStopsAndKeepsTheClosest) {
  TargetFigures first;
  first.samples = 500;
  for (int c = 0; c < validation::kNumTargetChecks; ++c) first.pairs[c] = 10;
  first.upper[1] = 0.03;  // 1.5x the far band's limit of 2%
  TargetFigures second = first;
  second.samples = 1000;
  second.upper[1] = 0.025;  // closer
  TargetFigures third = second;
  third.samples = 2000;
  third.upper[1] = 0.026;  // no closer than the second
  constexpr int64_t kBudget = validation::kMaxIndexBytes;
  NextStep next = DecideNext({first, second}, 1000, 8000, 0.005, 1 << 20, kBudget);
  EXPECT_FALSE(next.done);
  // A worst check that stays put while another falls is progress: go on.
  TargetFigures rms_stays = first;
  rms_stays.upper[0] = 0.006;  // 1.2x the RMS limit, the worst check, in both rounds
  TargetFigures far_falls = rms_stays;
  far_falls.samples = 1000;
  far_falls.upper[1] = 0.018;
  next = DecideNext({rms_stays, far_falls}, 1000, 8000, 0.005, 1 << 20, kBudget);
  EXPECT_FALSE(next.done);
  next = DecideNext({first, second, third}, 2000, 8000, 0.005, 1 << 20, kBudget);
  EXPECT_TRUE(next.done);
  EXPECT_FALSE(next.reached);
  EXPECT_EQ(next.keep, 1);
  EXPECT_EQ(next.stop, "round 3 came no closer to the target than round 2");
}

// A budget the target needs more than: the build stops at the last round
// whose index fits, says so, and its index is under the budget. A budget
// not even the first round fits is refused with the reason.
TEST(BuildRoundsTest, StopsAtTheLastRoundWithinTheBudget) {
  const mesh::Mesh m = mesh::gen::Sphere(4, 1.0);
  RoundsOptions options = Options(300, 1e-5);
  options.max_index_bytes = 1 << 20;
  absl::StatusOr<TargetBuild> result = BuildToTarget(m, {}, options, nullptr);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_FALSE(result->last.reached);
  EXPECT_NE(result->data.report.find("(the index size budget of 1 MiB)"), std::string::npos)
      << result->data.report;
  absl::StatusOr<std::string> bytes = index::SerializeIndex(result->data);
  ASSERT_TRUE(bytes.ok());
  EXPECT_LE(bytes->size(), size_t{1} << 20);
  // The prediction is the file's size.
  EXPECT_EQ(index::PredictIndexBytes(result->data), bytes->size());
  options.max_index_bytes = 64 << 10;
  EXPECT_EQ(BuildToTarget(m, {}, options, nullptr).status().code(),
            absl::StatusCode::kResourceExhausted);
}

TEST(BuildRoundsTest, TargetStateRoundTripsAndRefusesCorruption) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / "geodex_build_rounds_test_state").string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  EXPECT_EQ(LoadTargetState(dir).status().code(), absl::StatusCode::kNotFound);
  TargetState state;
  state.target = 0.005;
  state.cap = 8000;
  state.validation_sources = 128;
  state.seed = 7;
  state.split = false;
  state.max_index_bytes = 1 << 20;
  state.round = 1;
  state.closest = 0;
  TargetFigures f;
  f.samples = 512;
  f.upper[2] = 0.25;
  f.band_p99[1][3] = 0.03;
  f.band_pairs[1][3] = 321;
  f.unit = 0.01;
  state.rounds = {f};
  ASSERT_TRUE(SaveTargetState(state, dir).ok());
  absl::StatusOr<TargetState> loaded = LoadTargetState(dir);
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_EQ(loaded->target, 0.005);
  EXPECT_EQ(loaded->seed, 7u);
  EXPECT_FALSE(loaded->split);
  ASSERT_EQ(loaded->rounds.size(), 1u);
  EXPECT_EQ(loaded->rounds[0].samples, 512);
  EXPECT_EQ(loaded->rounds[0].upper[2], 0.25);
  EXPECT_EQ(loaded->rounds[0].band_p99[1][3], 0.03);
  EXPECT_EQ(loaded->rounds[0].band_pairs[1][3], 321);
  EXPECT_EQ(loaded->rounds[0].unit, 0.01);
  EXPECT_EQ(loaded->max_index_bytes, 1 << 20);
  EXPECT_EQ(loaded->closest, 0);
  state.round = 2;  // a round without its figures
  ASSERT_TRUE(SaveTargetState(state, dir).ok());
  EXPECT_EQ(LoadTargetState(dir).status().code(), absl::StatusCode::kDataLoss);
  ASSERT_TRUE(RemoveTargetState(dir).ok());
  EXPECT_EQ(LoadTargetState(dir).status().code(), absl::StatusCode::kNotFound);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace geodex::builder
