// geodex-build: the offline builder job (mesh -> .gdx index); the pipeline is
// core/builder/build_pipeline.h.
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
// .obj/.ply/.off file, or builtin:NAME (torus, sphere, cube, double-torus).
// Exit codes: 0 success, 2 bad input or usage, 1 any other failure, 3 merge
// planned another round of a target-error build (run rows and merge again).

#include <cstdio>

#include "CLI/CLI.hpp"
#include "core/builder/build_pipeline.h"
#include "core/builder/build_progress.h"
#include "core/builder/build_rounds.h"

namespace {

int ExitCode(const absl::StatusOr<geodex::builder::BuildReport>& report) {
  if (report.ok()) {
    std::fputs(report->text.c_str(), stdout);
    return report->another_round ? 3 : 0;
  }
  std::fprintf(stderr, "geodex-build: %s\n", report.status().ToString().c_str());
  switch (report.status().code()) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kOutOfRange:
    case absl::StatusCode::kNotFound:
      return 2;
    default:
      return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace geodex::builder;
  PipelineOptions o;
  ProgressPrinter printer;
  o.build.progress = [&printer](const Progress& p) { printer(p); };
  o.log = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  bool no_refinement = false, no_calibration = false;
  std::string mesh_path, out, workdir, shard, index_path;

  CLI::App app{"geodex-build: builds a geodex index (.gdx) from a triangle mesh."};
  app.require_subcommand(0, 1);
  CLI::App* plan_cmd = app.add_subcommand("plan", "Distributed build, step 1: sampling");
  CLI::App* rows_cmd = app.add_subcommand("rows", "Distributed build, step 2: one shard of rows");
  CLI::App* merge_cmd = app.add_subcommand(
      "merge",
      "Distributed build, step 3: the index (exit 3: a target-error build planned "
      "another round; run the rows and merge again)");
  CLI::App* calibrate_cmd = app.add_subcommand(
      "calibrate", "Adds the accuracy calibration (error bounds) to an index built without it");
  const auto threads = [&o](CLI::App* cmd) {
    cmd->add_option("--threads", o.build.threads, "Worker threads (0: all cores)")
        ->check(CLI::NonNegativeNumber);
  };
  const auto mesh_flags = [&](CLI::App* cmd) {
    cmd->add_flag("--strict", o.repair.strict,
                  "Refuse a mesh that needs repair (duplicate faces, non-manifold edges or "
                  "vertices, inconsistent orientation, zero-area faces) with the first reason, "
                  "instead of repairing it");
    cmd->add_option("--weld", o.repair.read.weld_tolerance,
                    "STL and glTF: weld corners closer than EPS times the bounding-box diagonal "
                    "(default 0: exactly equal positions)")
        ->check(CLI::Range(0.0, 1.0));
  };
  const auto sampling_flags = [&](CLI::App* cmd) {
    cmd->add_option("--samples", o.build.num_samples,
                    "Build exactly m samples (with --target-error: the first round's m)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--target-error", o.target_error,
                    "The error target (default 0.005 when --samples is not given): relative RMS "
                    "over area-uniform pairs <= E, p99 <= 2E below 3L and <= 4E from 3L, vertex "
                    "and interior pairs, by 95% upper limits on held-out sources")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--max-samples", o.max_samples,
                    "With an error target: the cap on m (default 8000; with --no-refinement, "
                    "half the vertices)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--seed", o.build.seed, "Sampling seed");
    cmd->add_option("--edges-obj", o.edges_obj, "Also write the geodesic edges as OBJ polylines");
    cmd->add_flag("--no-refinement", no_refinement,
                  "Sample the mesh's own vertices only: do not split edges longer than half the "
                  "sample spacing (coarse meshes then stop improving with more samples)");
    mesh_flags(cmd);
    threads(cmd);
  };
  app.add_option("mesh", mesh_path, "Mesh file (.obj/.ply/.off/.stl/.gltf/.glb) or builtin:NAME");
  app.add_option("-o,--output", out, "Output index file (.gdx)");
  sampling_flags(&app);
  plan_cmd->add_option("mesh", mesh_path, "Mesh file")->required();
  plan_cmd->add_option("-o,--output", workdir, "Work directory")->required();
  sampling_flags(plan_cmd);
  rows_cmd->add_option("workdir", workdir, "Work directory")->required();
  rows_cmd->add_option("--shard", shard, "Shard I/N (0-based I)")->required();
  threads(rows_cmd);
  merge_cmd->add_option("workdir", workdir, "Work directory")->required();
  merge_cmd->add_option("-o,--output", out, "Output index file (.gdx)")->required();
  threads(merge_cmd);
  for (CLI::App* cmd : {&app, merge_cmd}) {
    cmd->add_flag("--no-calibration", no_calibration,
                  "Skip the accuracy calibration (no error bounds or tolerance in queries)");
  }
  for (CLI::App* cmd : {&app, merge_cmd, calibrate_cmd}) {
    cmd->add_option("--report-png", o.report_png,
                    "Also draw the index's relative error by distance (p99, RMS, the target's "
                    "limit) as a PNG here");
  }
  calibrate_cmd->add_option("mesh", mesh_path, "The mesh the index was built from")->required();
  calibrate_cmd->add_option("index", index_path, "Index file (.gdx)")->required();
  calibrate_cmd->add_option("-o,--output", out, "Output index file (.gdx)")->required();
  mesh_flags(calibrate_cmd);
  threads(calibrate_cmd);
  CLI11_PARSE(app, argc, argv);
  o.build.refine_long_edges = !no_refinement;
  o.calibrate = !no_calibration;
  const CLI::App* sampled = *plan_cmd ? plan_cmd : &app;
  if (sampled->count("--samples") == 0) {
    o.build.num_samples = kDefaultFirstRoundSamples;
    if (o.target_error == 0) o.target_error = geodex::validation::kDefaultTargetError;
  }

  if (*plan_cmd) return ExitCode(PlanBuild(mesh_path, workdir, o));
  if (*rows_cmd) return ExitCode(ComputeShardRows(workdir, shard, o));
  if (*merge_cmd) return ExitCode(MergeBuild(workdir, out, o));
  if (*calibrate_cmd) return ExitCode(CalibrateIndexFile(mesh_path, index_path, out, o));
  if (mesh_path.empty() || out.empty()) {
    std::fprintf(stderr, "geodex-build: MESH and -o OUT.gdx are required\n%s", app.help().c_str());
    return 2;
  }
  return ExitCode(BuildIndexFile(mesh_path, out, o));
}
