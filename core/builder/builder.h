#pragma once

// The offline builder: mesh -> geodex index (paper §4).
//
//   1. Plan: farthest-point sampling, the geodesic Voronoi diagram and its
//      dual Delaunay triangulation, whose edges are traced as exact geodesics;
//      repaired until valid and no two edges cross (sampling, triangulation).
//   2. Rows: one full exact propagation per sample, in parallel: the sample
//      distance matrix row and the distances from the sample to every vertex
//      of its own and its neighbours' Voronoi cells. Shardable: any subset of
//      samples, on any machine.
//   3. Merge: every vertex picks the geodesic triangle around its own sample
//      in which its unfolded barycentric coordinates are most inside; the
//      index is assembled and validated.
//
// The three phases give byte-identical output whether they run in one process
// or as a plan / sharded rows / merge pipeline, whatever the thread counts.
//
// Thread safety: functions are reentrant; a Plan is immutable once made.

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/triangulation/geodesic_triangulation.h"

namespace geodex::builder {

inline constexpr char kBuilderVersion[] = "geodex-build 0.1.0";

struct Progress {
  const char* phase;  // "sampling", "repair", "rows", "merge"
  int64_t done;
  int64_t total;
};

struct BuildOptions {
  int32_t num_samples = 1000;
  uint64_t seed = 1;
  int threads = 0;  // 0: all hardware threads
  int32_t max_repair_rounds = 200;
  // Trace every Delaunay edge as an exact geodesic and repair edges that cross
  // (triangulation::RepairOptions::check_edges).
  bool check_edges = true;
  // Called from builder threads (serialised by the builder) as work advances.
  std::function<void(const Progress&)> progress;
};

struct Plan {
  uint64_t mesh_hash = 0;
  int32_t requested_samples = 0;
  uint64_t seed = 0;
  std::vector<int32_t> samples;  // vertex of each sample
  std::vector<int32_t> nearest;  // Voronoi cell (sample) of each vertex, kNone if unreferenced
  std::vector<std::array<int32_t, 3>> triangles;
  std::vector<std::array<int32_t, 3>> neighbors;
  triangulation::RepairReport repair;
  triangulation::EdgeStats edge_stats;  // of the final geodesic edges
  // The final geodesic edges when traced. Only in the process that made the
  // plan: the work directory keeps edge_stats, not the paths.
  std::vector<triangulation::GeodesicEdge> edges;
  double sampling_seconds = 0;
  double triangulation_seconds = 0;

  int32_t num_samples() const { return static_cast<int32_t>(samples.size()); }
  // Samples adjacent to `a` in the triangulation, sorted.
  std::vector<std::vector<int32_t>> SampleNeighbors() const;
};

// Exact distances computed from one sample.
struct SampleRow {
  int32_t sample = 0;
  std::vector<double> to_samples;  // d(sample, every sample), num_samples entries
  // d(sample, v) for every vertex v whose cell is the sample's or a
  // neighbour's, in increasing v.
  std::vector<double> to_cell_vertices;
};

struct BuildSummary {
  double sampling_seconds = 0;
  double triangulation_seconds = 0;
  double rows_seconds = 0;
  double merge_seconds = 0;
  int32_t requested_samples = 0;
  int32_t num_samples = 0;
  std::string repair;
  int32_t num_triangles = 0;
  int64_t referenced_vertices = 0;
  int64_t unassigned_vertices = 0;
  double share_outside = 0;  // vertices whose unfolded barycentrics leave [-0.01, 1.01]
  double longest_edge = 0;   // longest geodesic-triangle edge
  // Delaunay edges traced as exact geodesics (0 when not checked), pairs of
  // them found crossing over all repair rounds (the samples added for them are
  // in `repair`), and the lengths of the final traced edges.
  int32_t geodesic_edges = 0;
  int32_t edge_crossings_found = 0;
  double edge_length_total = 0;
  double edge_length_max = 0;
  double edge_length_error = 0;  // max |traced length - d(a,b)| / d(a,b)
  double bbox_diagonal = 0;
  uint64_t index_bytes = 0;
  // "key = value" lines without the timings (the index stores them, and the
  // same input must give the same bytes).
  std::string ToText() const;
};

absl::StatusOr<Plan> MakePlan(const mesh::Mesh& mesh, const BuildOptions& options);

// Full propagations from `sample_ids` (indices into plan.samples).
absl::StatusOr<std::vector<SampleRow>> ComputeRows(const mesh::Mesh& mesh, const Plan& plan,
                                                   std::span<const int32_t> sample_ids,
                                                   const BuildOptions& options);

// Assembles the index from the plan and the rows of every sample (any order).
// Errors: InvalidArgument if rows are missing, repeated or of the wrong size.
absl::StatusOr<index::IndexData> Merge(const mesh::Mesh& mesh, const Plan& plan,
                                       std::vector<SampleRow> rows, BuildSummary* summary);

// All three phases in one process.
absl::StatusOr<index::IndexData> BuildIndex(const mesh::Mesh& mesh, const BuildOptions& options,
                                            BuildSummary* summary);
// The rows and merge phases in one process, for a plan already made.
absl::StatusOr<index::IndexData> BuildIndexFromPlan(const mesh::Mesh& mesh, const Plan& plan,
                                                    const BuildOptions& options,
                                                    BuildSummary* summary);

}  // namespace geodex::builder
