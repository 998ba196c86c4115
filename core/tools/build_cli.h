#pragma once

// The geodex-build command line (core/tools/build_main.cc): its flags and
// subcommands, the pipeline options they resolve to, and the job they run
// (core/build/build_pipeline.h).
//
//   BuildCommandLine  the CLI11 app with the plan, rows, merge and calibrate
//                     subcommands, its flags bound to a BuildToolArgs
//   RunBuildJob       the pipeline call of a job
//   BuildExitCode     the process's exit status for a job's result
//
// Thread safety: a BuildCommandLine is used by one thread.

#include <string>

#include "CLI/CLI.hpp"
#include "absl/status/statusor.h"
#include "core/build/build_pipeline.h"

namespace geodex::tools {

// What geodex-build is asked, as its flags say.
struct BuildToolArgs {
  // Samples, target error, seed, threads, repair, edges file; completed by
  // BuildCommandLine::Options.
  builder::PipelineOptions pipeline;
  bool no_split = false;        // --no-split (hidden alias: --no-refinement)
  bool no_calibration = false;  // --no-calibration
  double max_index_mib = 0;     // --max-index-mib (0: the default budget)
  std::string mesh_path;        // a whole build, plan, calibrate
  std::string out;              // the index a whole build, merge or calibrate writes
  std::string workdir;          // plan (its -o), rows, merge
  std::string shard;            // rows: "I/N"
  std::string index_path;       // calibrate: the index to calibrate
};

// The job the parsed command line asks for: a whole build without a
// subcommand, else the subcommand's.
enum class BuildJob { kBuild, kPlan, kRows, kMerge, kCalibrate };

// The geodex-build app: parsing it (CLI11_PARSE) fills args(); CLI11 checks
// ranges, required arguments of subcommands, and that at most one
// subcommand is given.
class BuildCommandLine {
 public:
  BuildCommandLine();
  BuildCommandLine(const BuildCommandLine&) = delete;
  BuildCommandLine& operator=(const BuildCommandLine&) = delete;

  CLI::App& app() { return app_; }
  const BuildToolArgs& args() const { return args_; }

  // After parsing: the job given.
  BuildJob job() const;
  // After parsing: the pipeline options of args(), with the split and
  // calibration switches applied and, when --samples was not given (to a
  // whole build or plan), a build to the default error target from
  // builder::kDefaultFirstRoundSamples (--target-error E keeps E). Progress
  // and log are left empty for the caller.
  builder::PipelineOptions Options() const;
  // After parsing: what geodex-build prints on stderr before exiting 2 when a
  // whole build lacks MESH or -o (a line, then the help), or "" when the
  // arguments are complete.
  std::string MissingPathsMessage() const;

 private:
  void AddThreadsOption(CLI::App* cmd);
  void AddMeshOptions(CLI::App* cmd);
  void AddSamplingOptions(CLI::App* cmd);
  void AddSubcommandOptions();

  BuildToolArgs args_;
  CLI::App app_;
  CLI::App* plan_ = nullptr;
  CLI::App* rows_ = nullptr;
  CLI::App* merge_ = nullptr;
  CLI::App* calibrate_ = nullptr;
};

// Runs `job` on the paths of `args` with `options` (BuildCommandLine::Options,
// with progress and log as the caller wants them). Returns the pipeline
// call's report or error (build_pipeline.h).
absl::StatusOr<builder::BuildReport> RunBuildJob(BuildJob job, const BuildToolArgs& args,
                                                 const builder::PipelineOptions& options);

// 0 for a report, 3 for a merge that planned another round; for an error 2
// (InvalidArgument, OutOfRange, NotFound: bad input) or 1.
int BuildExitCode(const absl::StatusOr<builder::BuildReport>& report);

}  // namespace geodex::tools
