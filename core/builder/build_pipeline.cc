#include "core/builder/build_pipeline.h"

#include <chrono>
#include <cstdio>

#include "absl/strings/str_format.h"
#include "core/builder/build_progress.h"
#include "core/builder/mesh_arrays.h"
#include "core/builder/workdir.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/validation/calibration.h"
#include "core/validation/target_error.h"

namespace geodex::builder {
namespace {

// The value of report line `name` ("mesh_repairs"), or `absent`.
std::string ReportLine(const std::string& report, const std::string& name,
                       const std::string& absent) {
  const std::string key = name + " = ";
  const size_t at = report.find(key);
  if (at == std::string::npos) return absent;
  const size_t end = report.find('\n', at);
  return report.substr(at + key.size(), end == std::string::npos ? end : end - at - key.size());
}

std::string EdgeLine(int32_t edges, int32_t crossings, double total, double longest) {
  if (edges == 0) return "not traced";
  return absl::StrFormat(
      "%d traced as exact geodesics, %d crossing pairs found and repaired, "
      "total length %.6g, longest %.6g",
      edges, crossings, total, longest);
}

std::string SummaryText(const BuildSummary& s, const std::string& out, const std::string& repairs,
                        const std::string& refinement) {
  return absl::StrFormat(
      "geodex-build: wrote %s (%.1f MiB)\n"
      "  mesh repairs     %s\n"
      "  mesh refinement  %s\n"
      "  samples          %d requested, %d final (%s)\n"
      "  triangles        %d geodesic triangles\n"
      "  edges            %s\n"
      "  vertices         %lld referenced, %lld unassigned\n"
      "  outside [-0.01,1.01]  %.4f%% of vertices\n"
      "  longest edge     %.6g (%.4f of the bounding-box diagonal)\n"
      "  time             sampling %s, triangulation %s, rows %s, merge %s\n",
      out, s.index_bytes / 1048576.0, repairs, refinement, s.requested_samples, s.num_samples,
      s.repair, s.num_triangles,
      EdgeLine(s.geodesic_edges, s.edge_crossings_found, s.edge_length_total, s.edge_length_max),
      static_cast<long long>(s.referenced_vertices), static_cast<long long>(s.unassigned_vertices),
      100 * s.share_outside, s.longest_edge,
      s.bbox_diagonal > 0 ? s.longest_edge / s.bbox_diagonal : 0.0,
      FormatSeconds(s.sampling_seconds), FormatSeconds(s.triangulation_seconds),
      FormatSeconds(s.rows_seconds), FormatSeconds(s.merge_seconds));
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
// accuracy calibration (error bounds) and the figures in its report.
absl::Status AddCalibration(const mesh::Mesh& mesh, index::IndexData& data, int threads,
                            BuildReport* report) {
  const auto start = std::chrono::steady_clock::now();
  validation::CalibrationOptions options;
  options.pairs.threads = threads;
  GEODEX_RETURN_IF_ERROR(validation::AddCalibration(mesh, data, options));
  const index::AccuracyRecord& r = data.accuracy[0];
  data.report += validation::CalibrationText(r);
  report->text += absl::StrFormat(
      "  accuracy         relative error by scale (held-out pairs, default answer): RMS "
      "%.3f%% / %.3f%% / %.3f%% / %.3f%%, p99 %.3f%% / %.3f%% / %.3f%% / %.3f%% "
      "(d<L, L-3L, 3L-10L, >=10L; L = %.4g), calibrated in %s\n",
      100 * r.rms[0], 100 * r.rms[1], 100 * r.rms[2], 100 * r.rms[3], 100 * r.p99[0],
      100 * r.p99[1], 100 * r.p99[2], 100 * r.p99[3], r.scale_length,
      FormatSeconds(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()));
  return absl::OkStatus();
}

// Writes `data` to `out`, checks that it reads back, and adds the summary.
absl::Status WriteAndReport(const index::IndexData& data, BuildSummary& summary,
                            const std::string& out, BuildReport* report) {
  GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, out));
  GEODEX_ASSIGN_OR_RETURN(auto loaded, index::Index::Open(out));  // validate what we wrote
  summary.index_bytes = loaded->size_bytes();
  report->index_bytes = summary.index_bytes;
  report->num_samples = loaded->num_samples();
  report->text +=
      SummaryText(summary, out, ReportLine(data.report, "mesh_repairs", "none recorded"),
                  ReportLine(data.report, "mesh_refinement", "none (no edge longer than L/2)"));
  return absl::OkStatus();
}

void Log(const PipelineOptions& options, const std::string& line) {
  if (options.log) options.log(line);
}

absl::StatusOr<BuildReport> BuildToTargetError(const mesh::RepairedMesh& repaired,
                                               const std::string& out,
                                               const PipelineOptions& options) {
  validation::TargetErrorOptions target;
  target.target_rms = options.target_error;
  target.max_samples = options.max_samples;
  target.round_done = [&](int32_t round, const validation::TargetErrorRound& r) {
    Log(options, absl::StrFormat("[target-error] round %d: m = %d, relative RMS %.3f%% (95%% upper "
                                 "limit %.3f%%, target %.3f%%), p99 beyond 10L %.3f%% (upper limit "
                                 "%.3f%%, target %.3f%%)",
                                 round + 1, r.samples, 100 * r.rms, 100 * r.rms_upper,
                                 100 * options.target_error, 100 * r.far_p99, 100 * r.far_p99_upper,
                                 400 * options.target_error));
  };
  GEODEX_ASSIGN_OR_RETURN(auto result,
                          validation::BuildForTargetError(repaired.mesh, options.build, target,
                                                          RecordRepair(repaired)));
  result.data.report += absl::StrFormat(
      "target_error = %.6g\ntarget_error_reached = %s\ntarget_error_rounds = %d\n",
      options.target_error, result.reached ? "yes" : "no (sample cap)", result.rounds.size());
  result.data.report +=
      absl::StrFormat("target_error_rms_upper95 = %.6g\ntarget_error_far_p99_upper95 = %.6g\n",
                      result.rounds.back().rms_upper, result.rounds.back().far_p99_upper);
  result.data.report += validation::CalibrationText(result.data.accuracy[0]);
  if (!result.reached) {
    Log(options, absl::StrFormat("geodex-build: the target error was not reached at the cap of %d "
                                 "samples; writing the last round's index",
                                 result.rounds.back().samples));
  }
  BuildReport report;
  GEODEX_RETURN_IF_ERROR(WriteAndReport(result.data, result.summary, out, &report));
  return report;
}

}  // namespace

absl::StatusOr<mesh::RepairedMesh> LoadBuildInput(const std::string& path,
                                                  const mesh::RepairOptions& options) {
  const std::string prefix = "builtin:";
  if (path.rfind(prefix, 0) != 0) return mesh::LoadAndRepairMesh(path, options);
  const std::string name = path.substr(prefix.size());
  if (name == "torus") return mesh::WithoutRepairs(mesh::gen::Torus(96, 48, 2.0, 0.7));
  if (name == "sphere") return mesh::WithoutRepairs(mesh::gen::Sphere(5, 1.0));
  if (name == "cube") return mesh::WithoutRepairs(mesh::gen::Cube(24, 2.0));
  if (name == "double-torus") return mesh::WithoutRepairs(mesh::gen::DoubleTorus(24, 4.0));
  return absl::InvalidArgumentError(
      absl::StrFormat("unknown built-in mesh '%s' (torus, sphere, cube, double-torus)", name));
}

absl::StatusOr<BuildReport> BuildIndexFile(const std::string& mesh_path, const std::string& out,
                                           const PipelineOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::RepairedMesh repaired,
                          LoadBuildInput(mesh_path, options.repair));
  if (options.target_error > 0) return BuildToTargetError(repaired, out, options);
  GEODEX_ASSIGN_OR_RETURN(const PreparedMesh prepared,
                          PrepareMesh(repaired.mesh, RecordRepair(repaired),
                                      options.build.num_samples, options.build.refine_long_edges));
  const mesh::Mesh& mesh = prepared.mesh;
  GEODEX_ASSIGN_OR_RETURN(const Plan plan, MakePlan(mesh, options.build));
  BuildReport report;
  GEODEX_RETURN_IF_ERROR(WriteEdges(mesh, plan, options.edges_obj, &report));
  BuildSummary summary;
  GEODEX_ASSIGN_OR_RETURN(auto data, BuildIndexFromPlan(mesh, plan, options.build, &summary));
  AddRepair(prepared.record, &data);
  if (options.calibrate) {
    GEODEX_RETURN_IF_ERROR(AddCalibration(mesh, data, options.build.threads, &report));
  }
  GEODEX_RETURN_IF_ERROR(WriteAndReport(data, summary, out, &report));
  return report;
}

absl::StatusOr<BuildReport> PlanBuild(const std::string& mesh_path, const std::string& workdir,
                                      const PipelineOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::RepairedMesh repaired,
                          LoadBuildInput(mesh_path, options.repair));
  GEODEX_ASSIGN_OR_RETURN(const PreparedMesh prepared,
                          PrepareMesh(repaired.mesh, RecordRepair(repaired),
                                      options.build.num_samples, options.build.refine_long_edges));
  const mesh::Mesh& mesh = prepared.mesh;
  GEODEX_ASSIGN_OR_RETURN(const Plan plan, MakePlan(mesh, options.build));
  GEODEX_RETURN_IF_ERROR(SavePlan(mesh, plan, workdir));
  GEODEX_RETURN_IF_ERROR(SaveRepair(prepared.record, plan, workdir));
  BuildReport report;
  report.num_samples = plan.num_samples();
  report.text +=
      absl::StrFormat("geodex-build plan: mesh repairs: %s\n", repaired.report.Summary());
  report.text += absl::StrFormat("geodex-build plan: %d midpoints added by the flat refinement\n",
                                 prepared.record.refinement_vertices);
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
  GEODEX_ASSIGN_OR_RETURN(auto loaded, LoadPlan(workdir));
  const auto& [mesh, plan] = loaded;
  const std::vector<int32_t> ids = ShardSamples(plan.num_samples(), index, count);
  GEODEX_ASSIGN_OR_RETURN(auto rows, ComputeRows(mesh, plan, ids, options.build));
  GEODEX_RETURN_IF_ERROR(SaveRows(plan, rows, index, count, workdir));
  BuildReport report;
  report.num_samples = plan.num_samples();
  report.text +=
      absl::StrFormat("geodex-build rows: shard %d/%d, %zu samples\n", index, count, ids.size());
  return report;
}

absl::StatusOr<BuildReport> MergeBuild(const std::string& workdir, const std::string& out,
                                       const PipelineOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(auto loaded, LoadPlan(workdir));
  const auto& [mesh, plan] = loaded;
  GEODEX_ASSIGN_OR_RETURN(auto rows, LoadAllRows(plan, workdir));
  BuildSummary summary;
  GEODEX_ASSIGN_OR_RETURN(const RepairRecord repair, LoadRepair(plan, workdir));
  GEODEX_ASSIGN_OR_RETURN(auto data, Merge(mesh, plan, std::move(rows), &summary));
  AddRepair(repair, &data);
  BuildReport report;
  if (options.calibrate) {
    GEODEX_RETURN_IF_ERROR(AddCalibration(mesh, data, options.build.threads, &report));
  }
  GEODEX_RETURN_IF_ERROR(WriteAndReport(data, summary, out, &report));
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
                  index->refinement_vertices() > 0));
  const mesh::Mesh& mesh = prepared.mesh;
  if (index->header().mesh_hash != index::MeshHash(FlatPositions(mesh), FlatFaces(mesh))) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s was not built from %s", index_path, mesh_path));
  }
  index::IndexData data = index::ToIndexData(*index);
  BuildReport report;
  GEODEX_RETURN_IF_ERROR(AddCalibration(mesh, data, options.build.threads, &report));
  GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, out));
  report.text += absl::StrFormat("geodex-build calibrate: wrote %s\n", out);
  report.num_samples = index->num_samples();
  return report;
}

}  // namespace geodex::builder
