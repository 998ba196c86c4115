// geodex-build: the offline builder job (mesh -> .gdx index); the pipeline is
// core/build/build_pipeline.h, the command line core/tools/build_cli.h.
//
//   geodex-build MESH -o OUT.gdx [--target-error E] [--samples M0] [--max-samples CAP]
//   geodex-build MESH -o OUT.gdx --samples M [--threads N] [--seed S] [--edges-obj FILE]
//                [--report-png FILE]
//   geodex-build plan MESH [--target-error E | --samples M] [--seed S] -o WORKDIR
//   geodex-build rows WORKDIR --shard I/N [--threads T]
//   geodex-build merge WORKDIR -o OUT.gdx [--threads T]
//   geodex-build calibrate MESH INDEX.gdx -o OUT.gdx [--threads T]
//
// Without --samples the build is to an error target (E = 0.005 unless
// --target-error says otherwise; core/validation/target_error.h), in rounds
// from M0 = 500 samples; --samples alone builds exactly M. MESH is a
// .obj/.ply/.off file, or builtin:NAME (a generated demo mesh; --help lists them).
// Exit codes: 0 success, 2 bad input or usage, 1 any other failure, 3 merge
// planned another round of a target-error build (run rows and merge again).

#include <cstdio>
#include <string>

#include "CLI/CLI.hpp"
#include "core/builder/build_progress.h"
#include "core/tools/build_cli.h"

int main(int argc, char** argv) {
  using namespace geodex::builder;
  geodex::tools::BuildCommandLine command_line;
  CLI11_PARSE(command_line.app(), argc, argv);
  const std::string missing = command_line.MissingPathsMessage();
  if (!missing.empty()) {
    std::fputs(missing.c_str(), stderr);
    return 2;
  }
  PipelineOptions options = command_line.Options();
  ProgressPrinter printer;
  options.build.progress = [&printer](const Progress& p) { printer(p); };
  options.log = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const absl::StatusOr<BuildReport> report =
      geodex::tools::RunBuildJob(command_line.job(), command_line.args(), options);
  if (report.ok()) {
    std::fputs(report->text.c_str(), stdout);
  } else {
    std::fprintf(stderr, "geodex-build: %s\n", report.status().ToString().c_str());
  }
  return geodex::tools::BuildExitCode(report);
}
