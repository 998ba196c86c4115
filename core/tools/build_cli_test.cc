#include "core/tools/build_cli.h"

#include <filesystem>
#include <memory>
#include <string>

#include "core/build/build_rounds.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::tools {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

// A BuildCommandLine that has parsed `line` (without the program name).
std::unique_ptr<BuildCommandLine> Parsed(const std::string& line) {
  auto cli = std::make_unique<BuildCommandLine>();
  cli->app().parse(line, /*program_name_included=*/false);
  return cli;
}

std::string TestPath(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "geodex_build_cli_test";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

TEST(BuildCommandLineTest, WholeBuildDefaultsToTheErrorTarget) {
  const auto cli = Parsed("m.obj -o x.gdx");
  EXPECT_EQ(cli->job(), BuildJob::kBuild);
  EXPECT_EQ(cli->args().mesh_path, "m.obj");
  EXPECT_EQ(cli->args().out, "x.gdx");
  const builder::PipelineOptions o = cli->Options();
  EXPECT_EQ(o.build.num_samples, builder::kDefaultFirstRoundSamples);
  EXPECT_EQ(o.target_error, validation::kDefaultTargetError);
  EXPECT_TRUE(o.calibrate);
  EXPECT_TRUE(o.build.split_long_edges);
  EXPECT_EQ(cli->MissingPathsMessage(), "");
}

TEST(BuildCommandLineTest, SamplesAndTargetError) {
  builder::PipelineOptions o = Parsed("m.obj -o x.gdx --samples 40")->Options();
  EXPECT_EQ(o.build.num_samples, 40);
  EXPECT_EQ(o.target_error, 0);  // exactly m samples
  o = Parsed("m.obj -o x.gdx --samples 40 --target-error 0.01")->Options();
  EXPECT_EQ(o.build.num_samples, 40);
  EXPECT_EQ(o.target_error, 0.01);
  o = Parsed("m.obj -o x.gdx --target-error 0.01 --max-samples 900")->Options();
  EXPECT_EQ(o.build.num_samples, builder::kDefaultFirstRoundSamples);
  EXPECT_EQ(o.target_error, 0.01);
  EXPECT_EQ(o.max_samples, 900);
}

TEST(BuildCommandLineTest, WholeBuildFlags) {
  const auto cli = Parsed(
      "m.stl -o x.gdx --samples 40 --seed 9 --threads 3 --edges-obj e.obj --no-split "
      "--no-calibration --strict --weld 1e-6");
  const builder::PipelineOptions o = cli->Options();
  EXPECT_EQ(o.build.seed, 9u);
  EXPECT_EQ(o.build.threads, 3);
  EXPECT_EQ(o.edges_obj, "e.obj");
  EXPECT_FALSE(o.build.split_long_edges);
  EXPECT_FALSE(o.calibrate);
  EXPECT_TRUE(o.repair.strict);
  EXPECT_DOUBLE_EQ(o.repair.read.weld_tolerance, 1e-6);
}

TEST(BuildCommandLineTest, Subcommands) {
  auto cli = Parsed("plan m.obj -o wd --samples 30 --no-refinement");
  EXPECT_EQ(cli->job(), BuildJob::kPlan);
  EXPECT_EQ(cli->args().workdir, "wd");
  EXPECT_EQ(cli->Options().build.num_samples, 30);
  EXPECT_EQ(cli->Options().target_error, 0);
  EXPECT_FALSE(cli->Options().build.split_long_edges);  // --no-refinement: --no-split's old name
  EXPECT_EQ(Parsed("plan m.obj -o wd")->Options().target_error, validation::kDefaultTargetError);

  cli = Parsed("rows wd --shard 1/3 --threads 2");
  EXPECT_EQ(cli->job(), BuildJob::kRows);
  EXPECT_EQ(cli->args().shard, "1/3");
  EXPECT_EQ(cli->Options().build.threads, 2);
  EXPECT_EQ(cli->MissingPathsMessage(), "");

  cli = Parsed("merge wd -o x.gdx --no-calibration");
  EXPECT_EQ(cli->job(), BuildJob::kMerge);
  EXPECT_EQ(cli->args().out, "x.gdx");
  EXPECT_FALSE(cli->Options().calibrate);

  cli = Parsed("calibrate m.obj in.gdx -o out.gdx --strict");
  EXPECT_EQ(cli->job(), BuildJob::kCalibrate);
  EXPECT_EQ(cli->args().mesh_path, "m.obj");
  EXPECT_EQ(cli->args().index_path, "in.gdx");
  EXPECT_EQ(cli->args().out, "out.gdx");
  EXPECT_TRUE(cli->Options().repair.strict);
}

TEST(BuildCommandLineTest, RefusesWhatCli11Checks) {
  EXPECT_THROW(Parsed("rows wd"), CLI::RequiredError);
  EXPECT_THROW(Parsed("merge wd"), CLI::RequiredError);
  EXPECT_THROW(Parsed("m.obj -o x.gdx --samples 0"), CLI::ValidationError);
  EXPECT_THROW(Parsed("m.obj -o x.gdx --threads -1"), CLI::ValidationError);
  EXPECT_THROW(Parsed("rows wd --shard 0/1 --samples 5"), CLI::ExtrasError);
}

TEST(BuildCommandLineTest, MissingPathsMessageCarriesTheHelp) {
  for (const char* line : {"", "m.obj", "-o x.gdx --samples 5"}) {
    const auto cli = Parsed(line);
    const std::string message = cli->MissingPathsMessage();
    EXPECT_THAT(message, StartsWith("geodex-build: MESH and -o OUT.gdx are required\n")) << line;
    EXPECT_THAT(message, HasSubstr(cli->app().help())) << line;
  }
}

// Every built-in mesh is listed in --help, and the one a name does not
// match is refused with the list; each listed one builds.
TEST(BuildCommandLineTest, HelpListsTheBuiltInMeshes) {
  const std::string help = Parsed("m.obj -o x.gdx")->app().help();
  for (const char* name : {"torus", "sphere", "cube", "double-torus"}) {
    EXPECT_THAT(help, HasSubstr(name));
    EXPECT_THAT(builder::BuiltinMeshNames(), HasSubstr(name));
    EXPECT_TRUE(builder::LoadBuildInput(std::string("builtin:") + name, {}).ok()) << name;
  }
  const auto unknown = builder::LoadBuildInput("builtin:teapot", {});
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(unknown.status().message(), HasSubstr(builder::BuiltinMeshNames()));
}

TEST(BuildToolTest, ExitCodes) {
  EXPECT_EQ(BuildExitCode(builder::BuildReport{}), 0);
  builder::BuildReport another;
  another.another_round = true;
  EXPECT_EQ(BuildExitCode(another), 3);
  EXPECT_EQ(BuildExitCode(absl::InvalidArgumentError("x")), 2);
  EXPECT_EQ(BuildExitCode(absl::OutOfRangeError("x")), 2);
  EXPECT_EQ(BuildExitCode(absl::NotFoundError("x")), 2);
  EXPECT_EQ(BuildExitCode(absl::DataLossError("x")), 1);
}

TEST(BuildToolTest, RunsTheJobOfTheCommandLine) {
  const std::string index = TestPath("sphere.gdx");
  auto cli = Parsed("builtin:sphere -o " + index + " --samples 30 --threads 2 --no-calibration");
  absl::StatusOr<builder::BuildReport> report =
      RunBuildJob(cli->job(), cli->args(), cli->Options());
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(report->num_samples, 30);
  EXPECT_TRUE(std::filesystem::exists(index));

  cli = Parsed("builtin:nothing -o " + index + " --samples 30");
  report = RunBuildJob(cli->job(), cli->args(), cli->Options());
  EXPECT_EQ(BuildExitCode(report), 2);

  cli = Parsed("rows " + TestPath("no_workdir") + " --shard 0/1");
  report = RunBuildJob(cli->job(), cli->args(), cli->Options());
  EXPECT_FALSE(report.ok());

  cli = Parsed("calibrate " + TestPath("missing.obj") + " " + index + " -o " + index);
  report = RunBuildJob(cli->job(), cli->args(), cli->Options());
  EXPECT_EQ(BuildExitCode(report), 2);
  EXPECT_THAT(report.status().message(), HasSubstr("missing.obj"));
}

}  // namespace
}  // namespace geodex::tools
