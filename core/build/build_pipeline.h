#pragma once

// The geodex-build job as library calls; core/tools/build_cli.h is only
// their command line.
//
//   BuildIndexFile      mesh -> repair -> long-edge split -> plan -> rows ->
//                       merge -> calibration -> index file; to a fixed sample
//                       count, or to a target error in rounds
//   PlanBuild           the distributed build's step 1 (work directory, workdir.h)
//   ComputeShardRows    step 2, one shard of the rows
//   MergeBuild          step 3, the index
//   CalibrateIndexFile  the calibration of an index built without it
//
// Each returns the report geodex-build prints on stdout, or the first error.
// Errors: InvalidArgument for bad input (an unknown built-in mesh, a mesh the
// repair refuses or --strict refuses, a malformed shard, an index of another
// mesh), NotFound for a missing file, and the errors of the phases they run
// (builder.h, workdir.h, core/validation/calibration.h).
//
// This unit is its own CMake target above geodex_builder and
// geodex_validation: the calibration measures an index with the query
// engine, which the builder proper does not link.
//
// Thread safety: reentrant; concurrent calls must not share output paths or
// work directories.

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <utility>

#include "absl/status/statusor.h"
#include "core/builder/builder.h"
#include "core/mesh/mesh_repair.h"

namespace geodex::builder {

struct PipelineOptions {
  // m (the first round's with a target error), seed, threads, the
  // long-edge split, progress.
  BuildOptions build;
  // How the input mesh is repaired (strict: refused instead).
  mesh::RepairOptions repair;
  // Measure the index against held-out exact propagations and store its
  // error bounds (core/validation/calibration.h). A target-error build is
  // always calibrated: its validation is the calibration.
  bool calibrate = true;
  // > 0: build until the held-out error meets this target, in rounds from
  // build.num_samples (build_rounds.h; geodex-build's default is
  // validation::kDefaultTargetError from a predicted first round); 0: build
  // exactly build.num_samples samples.
  double target_error = 0;
  // With a target error: the cap on m (0: the default cap).
  int32_t max_samples = 0;
  // With a target error: no index over this many bytes is written (0:
  // validation::kMaxIndexBytes).
  int64_t max_index_bytes = 0;
  // Also write the geodesic Delaunay edges as OBJ polylines here.
  std::string edges_obj;
  // Also draw the written index's accuracy by distance as a PNG here
  // (core/index/report_chart.h; the index must be calibrated).
  std::string report_png;
  // Lines for the user about the rounds of a target-error build (stderr in
  // geodex-build); may be empty.
  std::function<void(const std::string&)> log;
};

struct BuildReport {
  std::string text;  // what geodex-build prints on stdout, line by line
  int32_t num_samples = 0;
  uint64_t index_bytes = 0;
  // MergeBuild of a target-error build's round that did not meet the target:
  // it planned the next round instead of writing the index; run the rows
  // shards and MergeBuild again.
  bool another_round = false;
};

// `options` of a build whose caller asked for a sample count
// (`samples_asked`: build.num_samples is the caller's) or did not: then the
// build is to the error target, validation::kDefaultTargetError unless
// target_error says otherwise, from a predicted first round. geodex-build
// (no --samples) and Python's geodex.build (no samples=) both call it, so
// the same request builds the same index.
PipelineOptions WithSampleDefaults(PipelineOptions options, bool samples_asked);

// The generated demo meshes builtin:NAME names, for help texts and errors:
// "torus, sphere, cube, double-torus".
std::string BuiltinMeshNames();

// The mesh at `path` (a mesh file core/mesh/mesh_io.h reads, or builtin:NAME
// for a generated demo mesh, BuiltinMeshNames()), read and repaired as
// `options` says.
absl::StatusOr<mesh::RepairedMesh> LoadBuildInput(const std::string& path,
                                                  const mesh::RepairOptions& options);

// The whole build in one process: writes the index of `mesh_path` to `out`.
absl::StatusOr<BuildReport> BuildIndexFile(const std::string& mesh_path, const std::string& out,
                                           const PipelineOptions& options);

// Step 1 of the distributed build: the (repaired, refined) mesh, its plan and
// the repair record into `workdir`.
absl::StatusOr<BuildReport> PlanBuild(const std::string& mesh_path, const std::string& workdir,
                                      const PipelineOptions& options);

// "I/N" with 0 <= I < N. Errors: InvalidArgument.
absl::StatusOr<std::pair<int32_t, int32_t>> ParseShard(std::string_view text);

// Step 2: the rows of shard `shard` ("I/N") of the plan in `workdir`.
absl::StatusOr<BuildReport> ComputeShardRows(const std::string& workdir, std::string_view shard,
                                             const PipelineOptions& options);

// Step 3: the index of `workdir` (its plan and every shard's rows) to `out`.
absl::StatusOr<BuildReport> MergeBuild(const std::string& workdir, const std::string& out,
                                       const PipelineOptions& options);

// Adds the calibration to `index_path`, built from `mesh_path` (refined again
// as the builder did; the mesh hash must match), and writes it to `out`.
absl::StatusOr<BuildReport> CalibrateIndexFile(const std::string& mesh_path,
                                               const std::string& index_path,
                                               const std::string& out,
                                               const PipelineOptions& options);

}  // namespace geodex::builder
