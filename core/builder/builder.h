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

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/builder/prepared_mesh.h"
#include "core/builder/plan.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"

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
  // Split long mesh edges flat before sampling (PrepareMesh in
  // core/builder/prepared_mesh.h; geodex-build --no-split turns it off).
  bool split_long_edges = true;
  // Error-driven placement (core/validation/error_map.h): one weight per
  // vertex of the mesh being built; farthest-point sampling then spaces the
  // samples about 1 / weight apart relative to elsewhere. Empty: plain
  // farthest-point sampling.
  std::vector<double> spacing_weight;
  // For refusal messages: the input file's id of each vertex of the mesh
  // being built (kNone for a midpoint of the long-edge split); empty when the
  // mesh's ids are the file's (InputVertexIds in prepared_mesh.h).
  std::vector<int32_t> input_vertex_ids;
  // Called from builder threads (serialised by the builder) as work advances.
  std::function<void(const Progress&)> progress;
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
  // The held-out validation (the calibration; every round's in a
  // target-error build).
  double validation_seconds = 0;
  int32_t requested_samples = 0;
  int32_t num_samples = 0;
  std::string repair;
  // The samples added for a wrong Euler characteristic (indices into the
  // samples, in the order added; triangulation::RepairReport::euler_samples).
  std::vector<int32_t> euler_samples;
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
  // same input must give the same bytes); repair_euler_samples only when
  // there are any.
  std::string ToText() const;
};

// Phase 1, the plan (paper §4.1): options.num_samples farthest-point samples
// from options.seed, their geodesic Voronoi diagram and its dual triangulation,
// repaired by adding samples until it is valid and, with options.check_edges,
// its traced geodesic edges do not cross. The same mesh and options give the
// same plan whatever options.threads (used to trace edges). Reports the
// "sampling" and "repair" phases through options.progress, from the calling
// thread.
// The repair may add samples up to 4 num_samples + 64 (256 at least), plus
// 16 for each handle or boundary loop and 4 for each component of the mesh.
// Errors: InvalidArgument if num_samples < 1 or exceeds the mesh's
// referenced vertices; FailedPrecondition when no valid triangulation is
// reached within max_repair_rounds rounds or the sample limit, naming the
// place in one line (triangulation::RepairTriangulation); errors of the exact
// propagation and of edge tracing.
// Thread safety: reentrant; `mesh` is only read.
absl::StatusOr<Plan> MakePlan(const mesh::Mesh& mesh, const BuildOptions& options);

// Phase 1 of a round that grows an earlier plan (a target-error build,
// core/build/build_rounds.h): the plan of options.num_samples samples on
// `mesh` whose first samples are `previous` (vertex ids of `mesh`, e.g. an
// earlier plan's samples on a mesh the split only added vertices to),
// the others added by farthest-point sampling from them and then by the
// repair, as MakePlan adds them. So the earlier rows stay rows of this plan
// (ComputeRows' `carried`). options.seed is recorded but not used.
// Errors: InvalidArgument if `previous` is empty, holds a vertex that is not
// a referenced vertex of `mesh` or a repeated one, or has more samples than
// options.num_samples; otherwise MakePlan's.
absl::StatusOr<Plan> ExtendPlan(const mesh::Mesh& mesh, std::span<const int32_t> previous,
                                const BuildOptions& options);

// Phase 2, the rows (paper §4.2's distances): one full exact propagation from
// each sample of `sample_ids` (indices into plan.samples; any subset, e.g. a
// shard), spread over options.threads threads. Returns the rows in the order
// of `sample_ids`; a row does not depend on the thread count or on which
// process computes it. Reports "rows" progress through options.progress from
// the worker threads, one call at a time.
//
// `carried` (a target-error build's later rounds): rows an earlier round
// computed for the first carried.size() samples of `plan` (ExtendPlan keeps
// them first), of which only to_samples is read. Such a sample's row takes
// over that to_samples (moved: the carried rows are left empty; the
// distances to the samples after it come from their rows, Merge reads
// either direction), and its cell distances come from a
// propagation that stops past its and its neighbours' cells (Plan's
// cell_radius bounds how far that is), a few percent of a full one; a full
// propagation when that bound does not hold.
// `coarse`, for a mesh whose long edges were split (CoarseSurfaceOf): the
// propagations run on the surface before the split, several times cheaper,
// and are read at the samples' and cell vertices' points; the distances are
// the split mesh's to rounding. Every process of a build passes the same.
// `coarse`, for a mesh whose long edges were split (CoarseSurfaceOf): the
// propagations run on the surface before the split, several times cheaper,
// and are read at the samples' and cell vertices' points; the distances are
// the split mesh's to rounding. Every process of one build passes the same.
// Errors: InvalidArgument for an id outside [0, plan.num_samples()), or a
// carried row that does not reach its own sample or has more entries than
// the plan has samples; an error of the exact propagation (then no rows are
// returned).
// Thread safety: reentrant; `mesh` and `plan` are only read.
absl::StatusOr<std::vector<SampleRow>> ComputeRows(const mesh::Mesh& mesh, const Plan& plan,
                                                   std::span<const int32_t> sample_ids,
                                                   const BuildOptions& options,
                                                   std::span<SampleRow> carried = {},
                                                   const index::CoarseSurface* coarse = nullptr);

// Phase 3: assembles the index from the plan and the rows of every sample (any
// order) and fills `summary` (vertex_assignment.h assigns the vertices).
// d(a, b) is the shorter of row a's entry b and row b's entry a, or the one
// there is: a row has an entry for every sample up to its own at least (a
// carried row of ComputeRows ends where its round's samples ended).
// Errors: InvalidArgument if rows are missing, repeated or of the wrong size;
// Internal if a referenced vertex's cell has no geodesic triangle.
// Thread safety: reentrant.
absl::StatusOr<index::IndexData> Merge(const mesh::Mesh& mesh, const Plan& plan,
                                       std::vector<SampleRow> rows, BuildSummary* summary);
// The same with the rows left in `rows`, sorted by sample (for the next round
// of a target-error build to carry).
absl::StatusOr<index::IndexData> MergeKeepingRows(const mesh::Mesh& mesh, const Plan& plan,
                                                  std::vector<SampleRow>* rows,
                                                  BuildSummary* summary);

// Everything of the index but the per-vertex records and the sample matrix:
// the header fields, the mesh, the samples, the geodesic triangles and the
// face BVH (what Merge adds to them; a builder predicts an index's bytes
// from it before the rows are computed).
void AddMeshAndTriangulation(const mesh::Mesh& mesh, const Plan& plan, index::IndexData* data);

// All three phases in one process.
absl::StatusOr<index::IndexData> BuildIndex(const mesh::Mesh& mesh, const BuildOptions& options,
                                            BuildSummary* summary);
// The rows and merge phases in one process, for a plan already made.
absl::StatusOr<index::IndexData> BuildIndexFromPlan(const mesh::Mesh& mesh, const Plan& plan,
                                                    const BuildOptions& options,
                                                    BuildSummary* summary,
                                                    const index::CoarseSurface* coarse = nullptr);

// BuildIndex on `prepared.mesh` with `prepared.record` added (AddRepair): the
// index a whole geodex-build makes, before its calibration.
absl::StatusOr<index::IndexData> BuildPreparedIndex(const PreparedMesh& prepared,
                                                    const BuildOptions& options,
                                                    BuildSummary* summary);

}  // namespace geodex::builder
