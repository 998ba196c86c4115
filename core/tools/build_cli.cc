#include "core/tools/build_cli.h"

#include <utility>

namespace geodex::tools {

BuildCommandLine::BuildCommandLine()
    : app_("geodex-build: builds a geodex index (.gdx) from a triangle mesh.") {
  app_.require_subcommand(0, 1);
  plan_ = app_.add_subcommand("plan", "Distributed build, step 1: sampling");
  rows_ = app_.add_subcommand("rows", "Distributed build, step 2: one shard of rows");
  merge_ = app_.add_subcommand(
      "merge",
      "Distributed build, step 3: the index (exit 3: a target-error build planned "
      "another round; run the rows and merge again)");
  calibrate_ = app_.add_subcommand(
      "calibrate", "Adds the accuracy calibration (error bounds) to an index built without it");
  app_.add_option("mesh", args_.mesh_path,
                  "Mesh file (.obj/.ply/.off/.stl/.gltf/.glb) or builtin:NAME, a generated "
                  "demo mesh: " +
                      builder::BuiltinMeshNames());
  app_.add_option("-o,--output", args_.out, "Output index file (.gdx)");
  AddSamplingOptions(&app_);
  AddSubcommandOptions();
}

void BuildCommandLine::AddThreadsOption(CLI::App* cmd) {
  cmd->add_option("--threads", args_.pipeline.build.threads, "Worker threads (0: all cores)")
      ->check(CLI::NonNegativeNumber);
}

void BuildCommandLine::AddMeshOptions(CLI::App* cmd) {
  cmd->add_flag("--strict", args_.pipeline.repair.strict,
                "Refuse a mesh that needs repair (duplicate faces, non-manifold edges or "
                "vertices, inconsistent orientation, zero-area faces) with the first reason, "
                "instead of repairing it");
  cmd->add_option("--weld", args_.pipeline.repair.read.weld_tolerance,
                  "STL and glTF: weld corners closer than EPS times the bounding-box diagonal "
                  "(default 0: exactly equal positions)")
      ->check(CLI::Range(0.0, 1.0));
}

void BuildCommandLine::AddSamplingOptions(CLI::App* cmd) {
  builder::PipelineOptions& o = args_.pipeline;
  cmd->add_option("--samples", o.build.num_samples,
                  "Build exactly m samples (with --target-error: the first round's m)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--target-error", o.target_error,
                  "The error target (default 0.005 when --samples is not given): relative RMS "
                  "over area-uniform pairs <= E and p99 <= 4E for pairs at least 8 L1000 apart "
                  "(L1000: the spacing of 1000 samples on the surface), vertex and interior "
                  "pairs, by 95% upper limits on held-out sources")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-index-mib", args_.max_index_mib,
                  "With an error target: no index over this many MiB is written; m stops at the "
                  "last round that fits (default 32)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-samples", o.max_samples,
                  "With an error target: the cap on m (default 8000; with --no-split, "
                  "half the vertices)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o.build.seed, "Sampling seed");
  cmd->add_option("--edges-obj", o.edges_obj, "Also write the geodesic edges as OBJ polylines");
  cmd->add_flag("--no-split", args_.no_split,
                "Sample the mesh's own vertices only: do not split edges longer than half the "
                "sample spacing (coarse meshes then stop improving with more samples)");
  // The flag's name before the split was called so; kept for scripts, not listed.
  cmd->add_flag("--no-refinement", args_.no_split)->group("");
  AddMeshOptions(cmd);
  AddThreadsOption(cmd);
}

void BuildCommandLine::AddSubcommandOptions() {
  plan_->add_option("mesh", args_.mesh_path, "Mesh file")->required();
  plan_->add_option("-o,--output", args_.workdir, "Work directory")->required();
  AddSamplingOptions(plan_);
  rows_->add_option("workdir", args_.workdir, "Work directory")->required();
  rows_->add_option("--shard", args_.shard, "Shard I/N (0-based I)")->required();
  AddThreadsOption(rows_);
  merge_->add_option("workdir", args_.workdir, "Work directory")->required();
  merge_->add_option("-o,--output", args_.out, "Output index file (.gdx)")->required();
  AddThreadsOption(merge_);
  for (CLI::App* cmd : {&app_, merge_}) {
    cmd->add_flag("--no-calibration", args_.no_calibration,
                  "Skip the accuracy calibration (no error bounds or tolerance in queries)");
  }
  for (CLI::App* cmd : {&app_, merge_, calibrate_}) {
    cmd->add_option("--report-png", args_.pipeline.report_png,
                    "Also draw the index's p99 relative error by L1000 band (vertex and interior "
                    "pairs, the target's limit where it judges) as a PNG here");
  }
  calibrate_->add_option("mesh", args_.mesh_path, "The mesh the index was built from")->required();
  calibrate_->add_option("index", args_.index_path, "Index file (.gdx)")->required();
  calibrate_->add_option("-o,--output", args_.out, "Output index file (.gdx)")->required();
  AddMeshOptions(calibrate_);
  AddThreadsOption(calibrate_);
}

BuildJob BuildCommandLine::job() const {
  if (*plan_) return BuildJob::kPlan;
  if (*rows_) return BuildJob::kRows;
  if (*merge_) return BuildJob::kMerge;
  if (*calibrate_) return BuildJob::kCalibrate;
  return BuildJob::kBuild;
}

builder::PipelineOptions BuildCommandLine::Options() const {
  builder::PipelineOptions o = args_.pipeline;
  o.build.split_long_edges = !args_.no_split;
  if (args_.max_index_mib > 0) {
    o.max_index_bytes = static_cast<int64_t>(args_.max_index_mib * 1048576.0);
  }
  o.calibrate = !args_.no_calibration;
  const CLI::App* sampled = *plan_ ? plan_ : &app_;
  return builder::WithSampleDefaults(std::move(o), sampled->count("--samples") > 0);
}

std::string BuildCommandLine::MissingPathsMessage() const {
  if (job() != BuildJob::kBuild || (!args_.mesh_path.empty() && !args_.out.empty())) return "";
  return "geodex-build: MESH and -o OUT.gdx are required\n" + app_.help();
}

absl::StatusOr<builder::BuildReport> RunBuildJob(BuildJob job, const BuildToolArgs& args,
                                                 const builder::PipelineOptions& options) {
  switch (job) {
    case BuildJob::kPlan:
      return builder::PlanBuild(args.mesh_path, args.workdir, options);
    case BuildJob::kRows:
      return builder::ComputeShardRows(args.workdir, args.shard, options);
    case BuildJob::kMerge:
      return builder::MergeBuild(args.workdir, args.out, options);
    case BuildJob::kCalibrate:
      return builder::CalibrateIndexFile(args.mesh_path, args.index_path, args.out, options);
    case BuildJob::kBuild:
      break;
  }
  return builder::BuildIndexFile(args.mesh_path, args.out, options);
}

int BuildExitCode(const absl::StatusOr<builder::BuildReport>& report) {
  if (report.ok()) return report->another_round ? 3 : 0;
  switch (report.status().code()) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kOutOfRange:
    case absl::StatusCode::kNotFound:
      return 2;
    default:
      return 1;
  }
}

}  // namespace geodex::tools
