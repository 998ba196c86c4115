// geodex-build: the offline builder job (mesh -> .gdx index).
//
//   geodex-build MESH -o OUT.gdx --samples M [--threads N] [--seed S] [--edges-obj FILE]
//   geodex-build MESH -o OUT.gdx --target-error E [--samples M0] [--max-samples CAP]
//   geodex-build plan MESH --samples M [--seed S] [--threads N] [--edges-obj FILE] -o WORKDIR
//   geodex-build rows WORKDIR --shard I/N [--threads T]
//   geodex-build merge WORKDIR -o OUT.gdx [--threads T]
//   geodex-build calibrate MESH INDEX.gdx -o OUT.gdx [--threads T]
//
// MESH is a .obj/.ply/.off file, or builtin:NAME for a generated demo mesh
// (torus, sphere, cube, double-torus). A file's mesh is repaired where that
// does not change the surface (core/mesh/mesh_repair.h: duplicate faces,
// non-manifold edges and vertices, orientation), each repair counted in the
// build report, and the index answers in the file's ids; --strict refuses
// such a mesh with the first reason instead. Edges longer than half the
// sample spacing L(m) are split flat first (core/builder/mesh_arrays.h,
// PrepareMesh: the surface is unchanged and the index still answers in the
// file's ids); --no-refinement keeps the mesh as it is. --edges-obj writes the geodesic
// Delaunay edges as OBJ polylines (v and l lines) to view over the mesh. Exit
// codes: 0 success, 2 bad input or usage, 1 any other failure.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <mutex>
#include <thread>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/builder/mesh_arrays.h"
#include "core/builder/workdir.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_repair.h"
#include "core/validation/calibration.h"
#include "core/validation/target_error.h"

namespace geodex {
namespace {

// The mesh to build from, repaired unless `strict` (then refused with the
// first reason, as Mesh::Create gives it).
absl::StatusOr<mesh::RepairedMesh> LoadInput(const std::string& path, bool strict) {
  const std::string prefix = "builtin:";
  if (path.rfind(prefix, 0) != 0) {
    mesh::RepairOptions options;
    options.strict = strict;
    return mesh::LoadAndRepairMesh(path, options);
  }
  const std::string name = path.substr(prefix.size());
  if (name == "torus") return mesh::WithoutRepairs(mesh::gen::Torus(96, 48, 2.0, 0.7));
  if (name == "sphere") return mesh::WithoutRepairs(mesh::gen::Sphere(5, 1.0));
  if (name == "cube") return mesh::WithoutRepairs(mesh::gen::Cube(24, 2.0));
  if (name == "double-torus") return mesh::WithoutRepairs(mesh::gen::DoubleTorus(24, 4.0));
  return absl::InvalidArgumentError(
      absl::StrFormat("unknown built-in mesh '%s' (torus, sphere, cube, double-torus)", name));
}

// The report's mesh_repairs line: the one-line summary.
// The value of report line `key` ("mesh_repairs"), or `absent`.
std::string ReportLine(const std::string& report, const std::string& name,
                       const std::string& absent) {
  const std::string key = name + " = ";
  const size_t at = report.find(key);
  if (at == std::string::npos) return absent;
  const size_t end = report.find('\n', at);
  return report.substr(at + key.size(), end == std::string::npos ? end : end - at - key.size());
}

std::string FormatSeconds(double s) {
  if (s < 60) return absl::StrFormat("%.1fs", s);
  return absl::StrFormat("%dm%02ds", static_cast<int>(s / 60), static_cast<int>(s) % 60);
}

// A live progress line with ETA on a terminal; a log line every 10 seconds
// (and at each phase's end) otherwise.
class ProgressPrinter {
 public:
  ProgressPrinter() : tty_(isatty(STDERR_FILENO)) {}

  void operator()(const builder::Progress& p) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    auto [it, inserted] = phase_start_.try_emplace(p.phase, now);
    const double elapsed = std::chrono::duration<double>(now - it->second).count();
    const double fraction = p.total > 0 ? static_cast<double>(p.done) / p.total : 1.0;
    std::string eta = "";
    if (fraction > 0 && fraction < 1) eta = " ETA " + FormatSeconds(elapsed / fraction - elapsed);
    const std::string line = absl::StrFormat("[%s] %d/%d (%.1f%%) elapsed %s%s", p.phase, p.done,
                                             p.total, 100 * fraction, FormatSeconds(elapsed), eta);
    if (tty_) {
      std::fprintf(stderr, "\r\033[K%s%s", line.c_str(), p.done >= p.total ? "\n" : "");
    } else if (p.done >= p.total || std::chrono::duration<double>(now - last_log_).count() >= 10) {
      std::fprintf(stderr, "%s\n", line.c_str());
      last_log_ = now;
    }
  }

 private:
  bool tty_;
  std::mutex mutex_;
  std::map<std::string, std::chrono::steady_clock::time_point> phase_start_;
  std::chrono::steady_clock::time_point last_log_{};
};

std::string EdgeLine(int32_t edges, int32_t crossings, double total, double longest) {
  if (edges == 0) return "not traced";
  return absl::StrFormat(
      "%d traced as exact geodesics, %d crossing pairs found and repaired, "
      "total length %.6g, longest %.6g",
      edges, crossings, total, longest);
}

void PrintSummary(const builder::BuildSummary& s, const std::string& out,
                  const std::string& repairs, const std::string& refinement) {
  std::printf(
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
      out.c_str(), s.index_bytes / 1048576.0, repairs.c_str(), refinement.c_str(),
      s.requested_samples, s.num_samples, s.repair.c_str(), s.num_triangles,
      EdgeLine(s.geodesic_edges, s.edge_crossings_found, s.edge_length_total, s.edge_length_max)
          .c_str(),
      static_cast<long long>(s.referenced_vertices), static_cast<long long>(s.unassigned_vertices),
      100 * s.share_outside, s.longest_edge,
      s.bbox_diagonal > 0 ? s.longest_edge / s.bbox_diagonal : 0.0,
      FormatSeconds(s.sampling_seconds).c_str(), FormatSeconds(s.triangulation_seconds).c_str(),
      FormatSeconds(s.rows_seconds).c_str(), FormatSeconds(s.merge_seconds).c_str());
}

// Writes the plan's traced edges for --edges-obj (nothing when `path` is empty).
absl::Status WriteEdges(const mesh::Mesh& mesh, const builder::Plan& plan,
                        const std::string& path) {
  if (path.empty()) return absl::OkStatus();
  GEODEX_RETURN_IF_ERROR(AtomicWriteFile(path, triangulation::EdgesToObj(mesh, plan.edges)));
  std::printf("geodex-build: wrote %zu geodesic edges to %s\n", plan.edges.size(), path.c_str());
  return absl::OkStatus();
}

// Measures the index against held-out exact propagations and stores its
// accuracy calibration (error bounds) and the figures in its report.
absl::Status AddCalibration(const mesh::Mesh& mesh, index::IndexData& data, int threads) {
  const auto start = std::chrono::steady_clock::now();
  validation::CalibrationOptions options;
  options.pairs.threads = threads;
  GEODEX_RETURN_IF_ERROR(validation::AddCalibration(mesh, data, options));
  const index::AccuracyRecord& r = data.accuracy[0];
  data.report += validation::CalibrationText(r);
  std::printf(
      "  accuracy         relative error by scale (held-out pairs, default answer): RMS "
      "%.3f%% / %.3f%% / %.3f%% / %.3f%%, p99 %.3f%% / %.3f%% / %.3f%% / %.3f%% "
      "(d<L, L-3L, 3L-10L, >=10L; L = %.4g), calibrated in %s\n",
      100 * r.rms[0], 100 * r.rms[1], 100 * r.rms[2], 100 * r.rms[3], 100 * r.p99[0],
      100 * r.p99[1], 100 * r.p99[2], 100 * r.p99[3], r.scale_length,
      FormatSeconds(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count())
          .c_str());
  return absl::OkStatus();
}

absl::Status WriteAndReport(const index::IndexData& data, builder::BuildSummary& summary,
                            const std::string& out) {
  GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, out));
  GEODEX_ASSIGN_OR_RETURN(auto loaded, index::Index::Open(out));  // validate what we wrote
  summary.index_bytes = loaded->size_bytes();
  PrintSummary(summary, out, ReportLine(data.report, "mesh_repairs", "none recorded"),
               ReportLine(data.report, "mesh_refinement", "none (no edge longer than L/2)"));
  return absl::OkStatus();
}

int ExitCode(const absl::Status& status) {
  if (status.ok()) return 0;
  std::fprintf(stderr, "geodex-build: %s\n", status.ToString().c_str());
  switch (status.code()) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kOutOfRange:
    case absl::StatusCode::kNotFound:
      return 2;
    default:
      return 1;
  }
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  using namespace geodex;
  CLI::App app{"geodex-build: builds a geodex index (.gdx) from a triangle mesh."};
  app.require_subcommand(0, 1);
  std::string mesh_path, out, workdir, shard_text, edges_obj;
  int32_t samples = 1000;
  uint64_t seed = 1;
  int threads = 0;
  app.add_option("mesh", mesh_path, "Mesh file (.obj/.ply/.off) or builtin:NAME");
  app.add_option("-o,--output", out, "Output index file (.gdx)");
  app.add_option("--samples", samples,
                 "Number of samples m (with --target-error: the first round's)")
      ->check(CLI::PositiveNumber);
  double target_error = 0;
  int32_t max_samples = 0;
  app.add_option("--target-error", target_error,
                 "Build until the held-out relative RMS is at most this (e.g. 0.005) and the "
                 "p99 beyond 10L at most 4x it, growing m by 1.5x per round")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-samples", max_samples,
                 "With --target-error: the cap on m (default 8000; with --no-refinement, half the "
                 "vertices)")
      ->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "Sampling seed");
  app.add_option("--threads", threads, "Worker threads (0: all cores)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--edges-obj", edges_obj, "Also write the geodesic edges as OBJ polylines");
  bool strict = false;
  const char* kStrictHelp =
      "Refuse a mesh that needs repair (duplicate faces, non-manifold edges or vertices, "
      "inconsistent orientation, zero-area faces) with the first reason, instead of repairing it";
  app.add_flag("--strict", strict, kStrictHelp);
  bool no_refinement = false;
  const char* kNoRefinementHelp =
      "Sample the mesh's own vertices only: do not split edges longer than half the sample "
      "spacing (coarse meshes then stop improving with more samples)";
  app.add_flag("--no-refinement", no_refinement, kNoRefinementHelp);

  CLI::App* plan_cmd = app.add_subcommand("plan", "Distributed build, step 1: sampling");
  plan_cmd->add_option("mesh", mesh_path, "Mesh file")->required();
  plan_cmd->add_option("--samples", samples, "Number of samples m")->check(CLI::PositiveNumber);
  plan_cmd->add_option("--seed", seed, "Sampling seed");
  plan_cmd->add_option("-o,--output", workdir, "Work directory")->required();
  plan_cmd->add_option("--threads", threads, "Worker threads (0: all cores)")
      ->check(CLI::NonNegativeNumber);
  plan_cmd->add_option("--edges-obj", edges_obj, "Also write the geodesic edges as OBJ polylines");
  plan_cmd->add_flag("--strict", strict, kStrictHelp);
  plan_cmd->add_flag("--no-refinement", no_refinement, kNoRefinementHelp);

  CLI::App* rows_cmd = app.add_subcommand("rows", "Distributed build, step 2: one shard of rows");
  rows_cmd->add_option("workdir", workdir, "Work directory")->required();
  rows_cmd->add_option("--shard", shard_text, "Shard I/N (0-based I)")->required();
  rows_cmd->add_option("--threads", threads, "Worker threads (0: all cores)")
      ->check(CLI::NonNegativeNumber);

  CLI::App* merge_cmd = app.add_subcommand("merge", "Distributed build, step 3: the index");
  merge_cmd->add_option("workdir", workdir, "Work directory")->required();
  merge_cmd->add_option("-o,--output", out, "Output index file (.gdx)")->required();
  merge_cmd->add_option("--threads", threads, "Calibration threads (0: all cores)")
      ->check(CLI::NonNegativeNumber);
  bool no_calibration = false;
  for (CLI::App* cmd : {&app, merge_cmd}) {
    cmd->add_flag("--no-calibration", no_calibration,
                  "Skip the accuracy calibration (no error bounds or tolerance in queries)");
  }

  std::string index_path;
  CLI::App* calibrate_cmd = app.add_subcommand(
      "calibrate", "Adds the accuracy calibration (error bounds) to an index built without it");
  calibrate_cmd->add_option("mesh", mesh_path, "The mesh the index was built from")->required();
  calibrate_cmd->add_option("index", index_path, "Index file (.gdx)")->required();
  calibrate_cmd->add_option("-o,--output", out, "Output index file (.gdx)")->required();
  calibrate_cmd->add_flag("--strict", strict, kStrictHelp);
  calibrate_cmd->add_option("--threads", threads, "Calibration threads (0: all cores)")
      ->check(CLI::NonNegativeNumber);

  CLI11_PARSE(app, argc, argv);

  ProgressPrinter printer;
  builder::BuildOptions options;
  options.num_samples = samples;
  options.seed = seed;
  options.threads = threads;
  options.refine_long_edges = !no_refinement;
  options.progress = [&printer](const builder::Progress& p) { printer(p); };

  absl::Status status;
  if (*plan_cmd) {
    status = [&]() -> absl::Status {
      GEODEX_ASSIGN_OR_RETURN(const mesh::RepairedMesh repaired, LoadInput(mesh_path, strict));
      GEODEX_ASSIGN_OR_RETURN(const builder::PreparedMesh prepared,
                              builder::PrepareMesh(repaired.mesh, builder::RecordRepair(repaired),
                                                   samples, options.refine_long_edges));
      const mesh::Mesh& mesh = prepared.mesh;
      GEODEX_ASSIGN_OR_RETURN(const builder::Plan plan, builder::MakePlan(mesh, options));
      GEODEX_RETURN_IF_ERROR(builder::SavePlan(mesh, plan, workdir));
      GEODEX_RETURN_IF_ERROR(builder::SaveRepair(prepared.record, plan, workdir));
      std::printf("geodex-build plan: mesh repairs: %s\n", repaired.report.Summary().c_str());
      std::printf("geodex-build plan: %d midpoints added by the flat refinement\n",
                  prepared.record.refinement_vertices);
      std::printf("geodex-build plan: %d samples (%s), %zu triangles, edges %s, in %s\n",
                  plan.num_samples(), plan.repair.Summary().c_str(), plan.triangles.size(),
                  EdgeLine(plan.edge_stats.count, plan.repair.crossings_found,
                           plan.edge_stats.total_length, plan.edge_stats.longest)
                      .c_str(),
                  workdir.c_str());
      return WriteEdges(mesh, plan, edges_obj);
    }();
  } else if (*rows_cmd) {
    status = [&]() -> absl::Status {
      int32_t shard = -1, num_shards = 0;
      char slash = 0;
      if (std::sscanf(shard_text.c_str(), "%d%c%d", &shard, &slash, &num_shards) != 3 ||
          slash != '/' || num_shards < 1 || shard < 0 || shard >= num_shards) {
        return absl::InvalidArgumentError(
            absl::StrFormat("--shard must be I/N with 0 <= I < N, got '%s'", shard_text));
      }
      GEODEX_ASSIGN_OR_RETURN(auto loaded, builder::LoadPlan(workdir));
      const auto& [mesh, plan] = loaded;
      const std::vector<int32_t> ids = builder::ShardSamples(plan.num_samples(), shard, num_shards);
      GEODEX_ASSIGN_OR_RETURN(auto rows, builder::ComputeRows(mesh, plan, ids, options));
      GEODEX_RETURN_IF_ERROR(builder::SaveRows(plan, rows, shard, num_shards, workdir));
      std::printf("geodex-build rows: shard %d/%d, %zu samples\n", shard, num_shards, ids.size());
      return absl::OkStatus();
    }();
  } else if (*merge_cmd) {
    status = [&]() -> absl::Status {
      GEODEX_ASSIGN_OR_RETURN(auto loaded, builder::LoadPlan(workdir));
      const auto& [mesh, plan] = loaded;
      GEODEX_ASSIGN_OR_RETURN(auto rows, builder::LoadAllRows(plan, workdir));
      builder::BuildSummary summary;
      GEODEX_ASSIGN_OR_RETURN(const builder::RepairRecord repair,
                              builder::LoadRepair(plan, workdir));
      GEODEX_ASSIGN_OR_RETURN(auto data, builder::Merge(mesh, plan, std::move(rows), &summary));
      builder::AddRepair(repair, &data);
      if (!no_calibration) GEODEX_RETURN_IF_ERROR(AddCalibration(mesh, data, threads));
      return WriteAndReport(data, summary, out);
    }();
  } else if (*calibrate_cmd) {
    status = [&]() -> absl::Status {
      GEODEX_ASSIGN_OR_RETURN(const mesh::RepairedMesh repaired, LoadInput(mesh_path, strict));
      GEODEX_ASSIGN_OR_RETURN(auto index, index::Index::Open(index_path));
      // The mesh the index was built from: refined again as the builder did
      // (deterministic), which the hash below confirms.
      GEODEX_ASSIGN_OR_RETURN(
          const builder::PreparedMesh prepared,
          builder::PrepareMesh(repaired.mesh, {},
                               static_cast<int32_t>(index->header().params.requested_samples),
                               index->refinement_vertices() > 0));
      const mesh::Mesh& mesh = prepared.mesh;
      if (index->header().mesh_hash !=
          index::MeshHash(builder::FlatPositions(mesh), builder::FlatFaces(mesh))) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s was not built from %s", index_path, mesh_path));
      }
      index::IndexData data = index::ToIndexData(*index);
      GEODEX_RETURN_IF_ERROR(AddCalibration(mesh, data, threads));
      GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, out));
      std::printf("geodex-build calibrate: wrote %s\n", out.c_str());
      return absl::OkStatus();
    }();
  } else {
    if (mesh_path.empty() || out.empty()) {
      std::fprintf(stderr, "geodex-build: MESH and -o OUT.gdx are required\n%s",
                   app.help().c_str());
      return 2;
    }
    status = [&]() -> absl::Status {
      GEODEX_ASSIGN_OR_RETURN(const mesh::RepairedMesh repaired, LoadInput(mesh_path, strict));
      if (target_error > 0) {
        validation::TargetErrorOptions target;
        target.target_rms = target_error;
        target.max_samples = max_samples;
        target.round_done = [&](int32_t round, const validation::TargetErrorRound& r) {
          std::fprintf(stderr,
                       "[target-error] round %d: m = %d, relative RMS %.3f%% (95%% upper limit "
                       "%.3f%%, target %.3f%%), p99 beyond 10L %.3f%% (upper limit %.3f%%, "
                       "target %.3f%%)\n",
                       round + 1, r.samples, 100 * r.rms, 100 * r.rms_upper, 100 * target_error,
                       100 * r.far_p99, 100 * r.far_p99_upper, 400 * target_error);
        };
        GEODEX_ASSIGN_OR_RETURN(auto result,
                                validation::BuildForTargetError(repaired.mesh, options, target,
                                                                builder::RecordRepair(repaired)));
        result.data.report += absl::StrFormat(
            "target_error = %.6g\ntarget_error_reached = %s\ntarget_error_rounds = %d\n",
            target_error, result.reached ? "yes" : "no (sample cap)", result.rounds.size());
        result.data.report += absl::StrFormat(
            "target_error_rms_upper95 = %.6g\ntarget_error_far_p99_upper95 = %.6g\n",
            result.rounds.back().rms_upper, result.rounds.back().far_p99_upper);
        result.data.report += validation::CalibrationText(result.data.accuracy[0]);
        if (!result.reached) {
          std::fprintf(stderr,
                       "geodex-build: the target error was not reached at the cap of %d "
                       "samples; writing the last round's index\n",
                       result.rounds.back().samples);
        }
        return WriteAndReport(result.data, result.summary, out);
      }
      GEODEX_ASSIGN_OR_RETURN(const builder::PreparedMesh prepared,
                              builder::PrepareMesh(repaired.mesh, builder::RecordRepair(repaired),
                                                   samples, options.refine_long_edges));
      const mesh::Mesh& mesh = prepared.mesh;
      GEODEX_ASSIGN_OR_RETURN(const builder::Plan plan, builder::MakePlan(mesh, options));
      GEODEX_RETURN_IF_ERROR(WriteEdges(mesh, plan, edges_obj));
      builder::BuildSummary summary;
      GEODEX_ASSIGN_OR_RETURN(auto data,
                              builder::BuildIndexFromPlan(mesh, plan, options, &summary));
      builder::AddRepair(prepared.record, &data);
      if (!no_calibration) GEODEX_RETURN_IF_ERROR(AddCalibration(mesh, data, threads));
      return WriteAndReport(data, summary, out);
    }();
  }
  return ExitCode(status);
}
