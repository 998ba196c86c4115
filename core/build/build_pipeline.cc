#include "core/build/build_pipeline.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/builder/build_progress.h"
#include "core/build/build_rounds.h"
#include "core/builder/mesh_arrays.h"
#include "core/builder/prepared_mesh.h"
#include "core/builder/workdir.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/index/index.h"
#include "core/index/index_report.h"
#include "core/index/report_chart.h"
#include "core/mesh/generators.h"
#include "core/validation/calibration.h"
#include "core/validation/target_error.h"

namespace geodex::builder {
namespace {

using Clock = std::chrono::steady_clock;

std::string EdgeLine(int32_t edges, int32_t crossings, double total, double longest) {
  if (edges == 0) return "not traced";
  return absl::StrFormat(
      "%d traced as exact geodesics, %d crossing pairs found and repaired, "
      "total length %.6g, longest %.6g",
      edges, crossings, total, longest);
}

// "12.3s in all: sampling 0.5s, ..., the rest (reading, repair, split,
// writing) 0.4s": the parts of `wall_seconds` (a build in one process), so
// that they add up to it; without it (the merge of a distributed build,
// whose sampling ran in another process) the parts only.
std::string TimeText(const BuildSummary& s, std::optional<double> wall_seconds) {
  const double parts[] = {s.sampling_seconds, s.triangulation_seconds, s.rows_seconds,
                          s.validation_seconds, s.merge_seconds};
  std::string text =
      absl::StrFormat("sampling %s, triangulation %s, rows %s, validation %s, merge %s",
                      FormatSeconds(parts[0]), FormatSeconds(parts[1]), FormatSeconds(parts[2]),
                      FormatSeconds(parts[3]), FormatSeconds(parts[4]));
  if (!wall_seconds.has_value()) return text;
  double rest = *wall_seconds;
  for (const double part : parts) rest -= part;
  return absl::StrFormat("%s in all: %s, the rest (reading, repair, split, writing) %s",
                         FormatSeconds(*wall_seconds), text, FormatSeconds(std::max(0.0, rest)));
}

// The closing lines of a build: the index's report (core/index/index_report.h),
// then what only the build knows: its triangulation's figures and its times.
std::string ClosingText(const BuildSummary& s, const index::IndexReport& report,
                        const std::string& out, std::optional<double> wall_seconds) {
  std::string text =
      absl::StrFormat("geodex-build: wrote %s\n%s", out, index::IndexReportText(report, out));
  absl::StrAppendFormat(
      &text,
      "  triangulation %s; %.2f%% of vertices outside [-0.01,1.01]; longest edge %.4f of the "
      "bounding-box diagonal\n",
      s.geodesic_edges == 0 ? std::string("edges not traced")
                            : absl::StrFormat("%d edges traced exactly, %d crossings repaired",
                                              s.geodesic_edges, s.edge_crossings_found),
      100 * s.share_outside, s.bbox_diagonal > 0 ? s.longest_edge / s.bbox_diagonal : 0.0);
  absl::StrAppendFormat(&text, "  time          %s\n", TimeText(s, wall_seconds));
  return text;
}

// Writes the report's chart to options.report_png, when asked for.
absl::Status WriteReportChart(const index::IndexReport& report, const PipelineOptions& options,
                              BuildReport* out) {
  if (options.report_png.empty()) return absl::OkStatus();
  GEODEX_RETURN_IF_ERROR(index::WriteReportPng(report, options.report_png));
  out->text +=
      absl::StrFormat("geodex-build: wrote the accuracy chart to %s\n", options.report_png);
  return absl::OkStatus();
}

// Writes the plan's traced edges (nothing when `path` is empty).
absl::Status WriteEdges(const mesh::Mesh& mesh, const Plan& plan, const std::string& path,
                        BuildReport* report) {
  if (path.empty()) return absl::OkStatus();
  GEODEX_RETURN_IF_ERROR(AtomicWriteFile(path, triangulation::EdgesToObj(mesh, plan.edges)));
  report->text +=
      absl::StrFormat("geodex-build: wrote %zu geodesic edges to %s\n", plan.edges.size(), path);
  return absl::OkStatus();
}

// Measures the index against held-out exact propagations and stores its
// accuracy calibration (error bounds) and the figures in its report;
// `seconds` receives the time it took.
absl::Status AddCalibration(const mesh::Mesh& mesh, index::IndexData& data, int threads,
                            double* seconds) {
  const auto start = std::chrono::steady_clock::now();
  validation::CalibrationOptions options;
  options.pairs.threads = threads;
  validation::Calibration calibration;
  GEODEX_RETURN_IF_ERROR(validation::AddCalibration(mesh, data, options, &calibration));
  data.report +=
      validation::BandsText(validation::FiguresOf(calibration, static_cast<int32_t>(data.samples.size())),
                            data.accuracy[0].scale_length) +
      validation::CalibrationText(data.accuracy[0]);
  *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return absl::OkStatus();
}

// Writes `data` to `out`, checks that it reads back, and adds the closing
// lines (and the chart), timed from `start` when the whole build ran in this
// process. No index over `budget` bytes (0: no budget) is written: the
// rounds predict their bytes, and this is the last word.
absl::Status WriteAndReport(const index::IndexData& data, BuildSummary& summary,
                            const std::string& out, const PipelineOptions& options,
                            std::optional<Clock::time_point> start, int64_t budget,
                            BuildReport* report) {
  const uint64_t bytes = index::PredictIndexBytes(data);
  if (budget > 0 && bytes > static_cast<uint64_t>(budget)) {
    return absl::ResourceExhaustedError(
        absl::StrFormat("the index would take %.2f MiB, over the index size budget of %s; "
                        "nothing was written",
                        bytes / 1048576.0, BudgetText(budget)));
  }
  GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, out));
  GEODEX_ASSIGN_OR_RETURN(auto loaded, index::Index::Open(out));  // validate what we wrote
  summary.index_bytes = loaded->size_bytes();
  report->index_bytes = summary.index_bytes;
  report->num_samples = loaded->num_samples();
  const index::IndexReport index_report = index::MakeIndexReport(*loaded);
  std::optional<double> wall_seconds;
  if (start.has_value()) {
    wall_seconds = std::chrono::duration<double>(Clock::now() - *start).count();
  }
  report->text += ClosingText(summary, index_report, out, wall_seconds);
  return WriteReportChart(index_report, options, report);
}

void Log(const PipelineOptions& options, const std::string& line) {
  if (options.log) options.log(line);
}

RoundsOptions RoundsOf(const PipelineOptions& options) {
  RoundsOptions rounds;
  rounds.build = options.build;
  rounds.target = options.target_error;
  rounds.max_samples = options.max_samples;
  if (options.max_index_bytes > 0) rounds.max_index_bytes = options.max_index_bytes;
  return rounds;
}

absl::StatusOr<BuildReport> BuildToTargetError(const mesh::RepairedMesh& repaired,
                                               const std::string& out,
                                               const PipelineOptions& options,
                                               Clock::time_point start) {
  GEODEX_ASSIGN_OR_RETURN(TargetBuild result, BuildToTarget(repaired.mesh, RecordRepair(repaired),
                                                            RoundsOf(options), options.log));
  if (!result.last.reached) {
    Log(options, absl::StrFormat("the target error was not reached (%s); "
                                 "writing the index of round %d (m = %d)",
                                 result.last.stop, result.last.keep + 1,
                                 result.rounds[result.last.keep].samples));
  }
  BuildReport report;
  GEODEX_RETURN_IF_ERROR(WriteEdges(result.mesh, result.plan, options.edges_obj, &report));
  GEODEX_RETURN_IF_ERROR(WriteAndReport(result.data, result.summary, out, options, start,
                                        RoundsOf(options).max_index_bytes, &report));
  return report;
}

// The first round of a distributed target-error build: the coarse mesh, the
// round's plan in its round directory, and the state.
absl::StatusOr<BuildReport> PlanTargetBuild(const mesh::RepairedMesh& repaired,
                                            const std::string& workdir,
                                            const PipelineOptions& options) {
  const RoundsOptions rounds = RoundsOf(options);
  const RepairRecord record = RecordRepair(repaired);
  GEODEX_ASSIGN_OR_RETURN(const RoundPlan round, PlanFirstRound(repaired.mesh, record, rounds));
  GEODEX_RETURN_IF_ERROR(SaveCoarseMesh(repaired.mesh, record, workdir));
  const std::string dir = RoundDirectory(workdir, 0);
  GEODEX_RETURN_IF_ERROR(SavePlan(round.prepared.mesh, round.plan, dir));
  GEODEX_RETURN_IF_ERROR(SaveRepair(round.prepared.record, round.plan, dir));
  GEODEX_RETURN_IF_ERROR(RemoveCarriedRows(dir));
  GEODEX_RETURN_IF_ERROR(RemoveRows(dir));
  TargetState state;
  state.target = rounds.target;
  state.cap = SampleCap(repaired.mesh, rounds);
  state.validation_sources = rounds.validation_sources;
  state.seed = rounds.build.seed;
  state.split = rounds.build.split_long_edges;
  state.max_index_bytes = rounds.max_index_bytes;
  GEODEX_RETURN_IF_ERROR(SaveTargetState(state, workdir));
  BuildReport report;
  report.num_samples = round.plan.num_samples();
  report.text += absl::StrFormat(
      "geodex-build plan: target error %g, round 1: %d samples (%s), %zu triangles, in %s\n",
      rounds.target, round.plan.num_samples(), round.plan.repair.Summary(),
      round.plan.triangles.size(), dir);
  GEODEX_RETURN_IF_ERROR(WriteEdges(round.prepared.mesh, round.plan, options.edges_obj, &report));
  return report;
}

// The directory of the current plan: the work directory of a fixed-m build,
// the current round's directory of a target-error build (with its state).
absl::StatusOr<std::string> CurrentPlanDirectory(const std::string& workdir,
                                                 std::optional<TargetState>* state) {
  absl::StatusOr<TargetState> loaded = LoadTargetState(workdir);
  if (absl::IsNotFound(loaded.status())) return workdir;
  GEODEX_RETURN_IF_ERROR(loaded.status());
  *state = *std::move(loaded);
  return RoundDirectory(workdir, (*state)->round);
}

// A finished round of a distributed target-error build: its merge and
// calibration, from the plan and rows in its directory.
absl::StatusOr<std::pair<RoundPlan, RoundResult>> FinishSavedRound(const std::string& dir,
                                                                   const RoundsOptions& rounds,
                                                                   std::vector<SampleRow>* rows) {
  GEODEX_ASSIGN_OR_RETURN(auto loaded, LoadPlan(dir));
  GEODEX_ASSIGN_OR_RETURN(RepairRecord record, LoadRepair(loaded.second, dir));
  RoundPlan round{
      PreparedMesh{std::move(loaded.first), std::move(record)}, std::move(loaded.second), {}};
  GEODEX_ASSIGN_OR_RETURN(*rows, LoadAllRows(round.plan, dir));
  GEODEX_ASSIGN_OR_RETURN(RoundResult result, FinishRound(round, rows, rounds));
  return std::make_pair(std::move(round), std::move(result));
}

// The rounds' options a distributed target-error build saved in its state.
RoundsOptions RoundsOfState(const TargetState& state, const PipelineOptions& options) {
  RoundsOptions rounds;
  rounds.build = options.build;
  rounds.build.seed = state.seed;
  rounds.build.split_long_edges = state.split;
  rounds.target = state.target;
  rounds.max_samples = state.cap;
  rounds.validation_sources = state.validation_sources;
  rounds.max_index_bytes = state.max_index_bytes;
  return rounds;
}

// The index of a finished target-error build: round next.keep's, `result`
// when that is the round just merged, with the rounds' report.
absl::StatusOr<BuildReport> WriteClosestRound(const std::string& workdir, const TargetState& state,
                                              const NextStep& next, const RoundsOptions& rounds,
                                              RoundResult result, const std::string& out,
                                              const PipelineOptions& options) {
  if (next.keep != state.round) {
    // A later round came no closer: the closest one's index, made again
    // from its directory (merge and calibration are deterministic).
    std::vector<SampleRow> kept_rows;
    GEODEX_ASSIGN_OR_RETURN(
        auto kept, FinishSavedRound(RoundDirectory(workdir, next.keep), rounds, &kept_rows));
    result = std::move(kept.second);
  }
  result.data.report += TargetReport(state.rounds, next, state.target, result.data.accuracy[0]);
  if (!next.reached) {
    Log(options, absl::StrFormat("the target error was not reached (%s); "
                                 "writing the index of round %d (m = %d)",
                                 next.stop, next.keep + 1, state.rounds[next.keep].samples));
  }
  result.summary.validation_seconds = result.validation_seconds;
  BuildReport report;
  GEODEX_RETURN_IF_ERROR(WriteAndReport(result.data, result.summary, out, options, std::nullopt,
                                        state.max_index_bytes, &report));
  return report;
}

// The next round's directory: its plan, repair record and carried rows, and
// no rows yet.
absl::Status SaveNextRound(const RoundPlan& following, const std::string& next_dir) {
  GEODEX_RETURN_IF_ERROR(SavePlan(following.prepared.mesh, following.plan, next_dir));
  GEODEX_RETURN_IF_ERROR(SaveRepair(following.prepared.record, following.plan, next_dir));
  GEODEX_RETURN_IF_ERROR(RemoveRows(next_dir));
  if (following.carried.empty()) return RemoveCarriedRows(next_dir);
  return SaveCarriedRows(following.plan, following.carried, next_dir);
}

// Merge of a target-error build's round: the index when the build is done
// (the target met, or m can grow no more: the closest round's index),
// otherwise the next round's plan.
absl::StatusOr<BuildReport> MergeTargetRound(const std::string& workdir, TargetState state,
                                             const std::string& out,
                                             const PipelineOptions& options) {
  const std::string dir = RoundDirectory(workdir, state.round);
  const RoundsOptions rounds = RoundsOfState(state, options);
  std::vector<SampleRow> rows;
  GEODEX_ASSIGN_OR_RETURN(auto finished, FinishSavedRound(dir, rounds, &rows));
  RoundPlan& round = finished.first;
  RoundResult& result = finished.second;
  state.rounds.push_back(result.figures);
  Log(options, RoundLine(state.round, result.figures, state.target));
  NextStep next = DecideNext(state.rounds, round.plan.requested_samples, state.cap, state.target,
                             static_cast<int64_t>(index::PredictIndexBytes(result.data)),
                             state.max_index_bytes);
  std::optional<RoundPlan> following;
  if (!next.done) {
    GEODEX_ASSIGN_OR_RETURN(auto coarse, LoadCoarseMesh(workdir));
    absl::StatusOr<RoundPlan> planned = PlanNextRound(coarse.first, coarse.second, round,
                                                      std::move(rows), next.num_samples, rounds);
    if (absl::IsResourceExhausted(planned.status())) {
      next = AtBudget(state.rounds, state.max_index_bytes);
    } else {
      GEODEX_RETURN_IF_ERROR(planned.status());
      following = *std::move(planned);
    }
  }
  if (next.done) {
    return WriteClosestRound(workdir, state, next, rounds, std::move(result), out, options);
  }
  // The next round's directory is complete before the state points at it:
  // a merge killed before that point is run again, from this round.
  const std::string next_dir = RoundDirectory(workdir, state.round + 1);
  GEODEX_RETURN_IF_ERROR(SaveNextRound(*following, next_dir));
  // Not done: this round is the closest so far (DecideNext stops at the
  // first that is not). Its directory is kept; the one it replaces is not.
  const int32_t replaced = state.closest;
  state.closest = state.round;
  ++state.round;
  GEODEX_RETURN_IF_ERROR(SaveTargetState(state, workdir));
  if (replaced >= 0) {
    std::error_code ignored;
    std::filesystem::remove_all(RoundDirectory(workdir, replaced), ignored);
  }
  BuildReport report;
  report.another_round = true;
  report.num_samples = following->plan.num_samples();
  report.text += absl::StrFormat(
      "geodex-build merge: target not met; round %d planned with %d samples (%d carried) in %s: "
      "run the rows shards and merge again\n",
      state.round + 1, following->plan.num_samples(), following->carried.size(), next_dir);
  return report;
}

}  // namespace

PipelineOptions WithSampleDefaults(PipelineOptions options, bool samples_asked) {
  if (!samples_asked) {
    options.build.num_samples = kDefaultFirstRoundSamples;
    if (options.target_error == 0) options.target_error = validation::kDefaultTargetError;
  }
  return options;
}

namespace {

// The demo meshes by name, in the order help texts list them.
struct BuiltinMesh {
  const char* name;
  mesh::Mesh (*make)();
};
constexpr BuiltinMesh kBuiltinMeshes[] = {
    {"torus", [] { return mesh::gen::Torus(96, 48, 2.0, 0.7); }},
    {"sphere", [] { return mesh::gen::Sphere(5, 1.0); }},
    {"cube", [] { return mesh::gen::Cube(24, 2.0); }},
    {"double-torus", [] { return mesh::gen::DoubleTorus(24, 4.0); }},
};

}  // namespace

std::string BuiltinMeshNames() {
  std::string names;
  for (const BuiltinMesh& m : kBuiltinMeshes) {
    absl::StrAppend(&names, names.empty() ? "" : ", ", m.name);
  }
  return names;
}

absl::StatusOr<mesh::RepairedMesh> LoadBuildInput(const std::string& path,
                                                  const mesh::RepairOptions& options) {
  const std::string prefix = "builtin:";
  if (path.rfind(prefix, 0) != 0) return mesh::LoadAndRepairMesh(path, options);
  const std::string name = path.substr(prefix.size());
  for (const BuiltinMesh& m : kBuiltinMeshes) {
    if (name == m.name) return mesh::WithoutRepairs(m.make());
  }
  return absl::InvalidArgumentError(
      absl::StrFormat("unknown built-in mesh '%s' (%s)", name, BuiltinMeshNames()));
}

absl::StatusOr<BuildReport> BuildIndexFile(const std::string& mesh_path, const std::string& out,
                                           const PipelineOptions& options) {
  const Clock::time_point start = Clock::now();
  GEODEX_ASSIGN_OR_RETURN(const mesh::RepairedMesh repaired,
                          LoadBuildInput(mesh_path, options.repair));
  if (options.target_error > 0) return BuildToTargetError(repaired, out, options, start);
  GEODEX_ASSIGN_OR_RETURN(const PreparedMesh prepared,
                          PrepareMesh(repaired.mesh, RecordRepair(repaired),
                                      options.build.num_samples, options.build.split_long_edges));
  const mesh::Mesh& mesh = prepared.mesh;
  BuildOptions build = options.build;
  build.input_vertex_ids = InputVertexIds(prepared);
  GEODEX_ASSIGN_OR_RETURN(const Plan plan, MakePlan(mesh, build));
  BuildReport report;
  GEODEX_RETURN_IF_ERROR(WriteEdges(mesh, plan, options.edges_obj, &report));
  BuildSummary summary;
  GEODEX_ASSIGN_OR_RETURN(const std::optional<index::CoarseSurface> surface,
                          CoarseSurfaceOf(mesh, prepared.record));
  GEODEX_ASSIGN_OR_RETURN(auto data, BuildIndexFromPlan(mesh, plan, options.build, &summary,
                                                        surface ? &*surface : nullptr));
  AddRepair(prepared.record, &data);
  if (options.calibrate) {
    GEODEX_RETURN_IF_ERROR(
        AddCalibration(mesh, data, options.build.threads, &summary.validation_seconds));
  }
  GEODEX_RETURN_IF_ERROR(
      WriteAndReport(data, summary, out, options, start, options.max_index_bytes, &report));
  return report;
}

absl::StatusOr<BuildReport> PlanBuild(const std::string& mesh_path, const std::string& workdir,
                                      const PipelineOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::RepairedMesh repaired,
                          LoadBuildInput(mesh_path, options.repair));
  if (options.target_error > 0) return PlanTargetBuild(repaired, workdir, options);
  GEODEX_RETURN_IF_ERROR(RemoveTargetState(workdir));
  GEODEX_ASSIGN_OR_RETURN(const PreparedMesh prepared,
                          PrepareMesh(repaired.mesh, RecordRepair(repaired),
                                      options.build.num_samples, options.build.split_long_edges));
  const mesh::Mesh& mesh = prepared.mesh;
  BuildOptions build = options.build;
  build.input_vertex_ids = InputVertexIds(prepared);
  GEODEX_ASSIGN_OR_RETURN(const Plan plan, MakePlan(mesh, build));
  GEODEX_RETURN_IF_ERROR(SavePlan(mesh, plan, workdir));
  GEODEX_RETURN_IF_ERROR(SaveRepair(prepared.record, plan, workdir));
  BuildReport report;
  report.num_samples = plan.num_samples();
  report.text +=
      absl::StrFormat("geodex-build plan: mesh repairs: %s\n", repaired.report.Summary());
  report.text += absl::StrFormat("geodex-build plan: %d midpoints added by the long-edge split\n",
                                 prepared.record.split_vertices);
  report.text +=
      absl::StrFormat("geodex-build plan: %d samples (%s), %zu triangles, edges %s, in %s\n",
                      plan.num_samples(), plan.repair.Summary(), plan.triangles.size(),
                      EdgeLine(plan.edge_stats.count, plan.repair.crossings_found,
                               plan.edge_stats.total_length, plan.edge_stats.longest),
                      workdir);
  GEODEX_RETURN_IF_ERROR(WriteEdges(mesh, plan, options.edges_obj, &report));
  return report;
}

absl::StatusOr<std::pair<int32_t, int32_t>> ParseShard(std::string_view text) {
  int32_t shard = -1, num_shards = 0;
  char slash = 0, extra = 0;
  const std::string copy(text);
  if (std::sscanf(copy.c_str(), "%d%c%d%c", &shard, &slash, &num_shards, &extra) != 3 ||
      slash != '/' || num_shards < 1 || shard < 0 || shard >= num_shards) {
    return absl::InvalidArgumentError(
        absl::StrFormat("--shard must be I/N with 0 <= I < N, got '%s'", copy));
  }
  return std::make_pair(shard, num_shards);
}

absl::StatusOr<BuildReport> ComputeShardRows(const std::string& workdir, std::string_view shard,
                                             const PipelineOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(const auto parsed, ParseShard(shard));
  const auto [index, count] = parsed;
  std::optional<TargetState> state;
  GEODEX_ASSIGN_OR_RETURN(const std::string dir, CurrentPlanDirectory(workdir, &state));
  GEODEX_ASSIGN_OR_RETURN(auto loaded, LoadPlan(dir));
  const auto& [mesh, plan] = loaded;
  GEODEX_ASSIGN_OR_RETURN(std::vector<SampleRow> carried, LoadCarriedRows(plan, dir));
  GEODEX_ASSIGN_OR_RETURN(const RepairRecord repair, LoadRepair(plan, dir));
  GEODEX_ASSIGN_OR_RETURN(const std::optional<index::CoarseSurface> surface,
                          CoarseSurfaceOf(mesh, repair));
  const std::vector<int32_t> ids = ShardSamples(plan.num_samples(), index, count);
  GEODEX_ASSIGN_OR_RETURN(auto rows, ComputeRows(mesh, plan, ids, options.build, carried,
                                                 surface ? &*surface : nullptr));
  GEODEX_RETURN_IF_ERROR(SaveRows(plan, rows, index, count, dir));
  BuildReport report;
  report.num_samples = plan.num_samples();
  report.text +=
      absl::StrFormat("geodex-build rows: shard %d/%d, %zu samples\n", index, count, ids.size());
  return report;
}

absl::StatusOr<BuildReport> MergeBuild(const std::string& workdir, const std::string& out,
                                       const PipelineOptions& options) {
  std::optional<TargetState> state;
  GEODEX_ASSIGN_OR_RETURN(const std::string dir, CurrentPlanDirectory(workdir, &state));
  if (state.has_value()) return MergeTargetRound(workdir, *std::move(state), out, options);
  GEODEX_ASSIGN_OR_RETURN(auto loaded, LoadPlan(workdir));
  const auto& [mesh, plan] = loaded;
  GEODEX_ASSIGN_OR_RETURN(auto rows, LoadAllRows(plan, workdir));
  BuildSummary summary;
  GEODEX_ASSIGN_OR_RETURN(const RepairRecord repair, LoadRepair(plan, workdir));
  GEODEX_ASSIGN_OR_RETURN(auto data, Merge(mesh, plan, std::move(rows), &summary));
  AddRepair(repair, &data);
  BuildReport report;
  if (options.calibrate) {
    GEODEX_RETURN_IF_ERROR(
        AddCalibration(mesh, data, options.build.threads, &summary.validation_seconds));
  }
  GEODEX_RETURN_IF_ERROR(
      WriteAndReport(data, summary, out, options, std::nullopt, options.max_index_bytes, &report));
  return report;
}

absl::StatusOr<BuildReport> CalibrateIndexFile(const std::string& mesh_path,
                                               const std::string& index_path,
                                               const std::string& out,
                                               const PipelineOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::RepairedMesh repaired,
                          LoadBuildInput(mesh_path, options.repair));
  GEODEX_ASSIGN_OR_RETURN(auto index, index::Index::Open(index_path));
  // The mesh the index was built from: refined again as the builder did
  // (deterministic), which the hash below confirms.
  GEODEX_ASSIGN_OR_RETURN(
      const PreparedMesh prepared,
      PrepareMesh(repaired.mesh, {}, static_cast<int32_t>(index->header().params.requested_samples),
                  index->split_vertices() > 0));
  const mesh::Mesh& mesh = prepared.mesh;
  if (index->header().mesh_hash != index::MeshHash(FlatPositions(mesh), FlatFaces(mesh))) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s was not built from %s", index_path, mesh_path));
  }
  index::IndexData data = index::ToIndexData(*index);
  BuildReport report;
  double seconds = 0;
  GEODEX_RETURN_IF_ERROR(AddCalibration(mesh, data, options.build.threads, &seconds));
  GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, out));
  GEODEX_ASSIGN_OR_RETURN(auto calibrated, index::Index::Open(out));  // validate what we wrote
  const index::IndexReport index_report = index::MakeIndexReport(*calibrated);
  report.text +=
      absl::StrFormat("geodex-build calibrate: wrote %s\n%s  time          calibration %s\n", out,
                      index::IndexReportText(index_report, out), FormatSeconds(seconds));
  report.num_samples = index->num_samples();
  GEODEX_RETURN_IF_ERROR(WriteReportChart(index_report, options, &report));
  return report;
}

}  // namespace geodex::builder
