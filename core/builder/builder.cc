#include "core/builder/builder.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "core/builder/mesh_arrays.h"
#include "core/builder/prepared_mesh.h"
#include "core/builder/vertex_assignment.h"
#include "core/common/status_macros.h"
#include "core/common/threads.h"
#include "core/geodesic/vertex_geodesic.h"
#include "core/index/face_bvh.h"
#include "core/sampling/farthest_point_sampling.h"

namespace geodex::builder {
namespace {

using mesh::kNone;
using mesh::Mesh;
using mesh::SurfacePoint;

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int ThreadCount(const BuildOptions& options) { return common::ThreadCount(options.threads); }

// Merge's steps.

// Sorts the rows by sample and checks there is one per sample, each with a
// distance to every sample. Errors: InvalidArgument.
absl::Status SortAndCheckRows(int32_t num_samples, std::vector<SampleRow>* rows) {
  if (static_cast<int32_t>(rows->size()) != num_samples) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "merge needs the rows of all %d samples, got %d", num_samples, rows->size()));
  }
  std::sort(rows->begin(), rows->end(),
            [](const SampleRow& x, const SampleRow& y) { return x.sample < y.sample; });
  for (int32_t a = 0; a < num_samples; ++a) {
    if ((*rows)[a].sample != a) {
      return absl::InvalidArgumentError(absl::StrFormat("row of sample %d missing or repeated", a));
    }
    // A carried row ends where its round's samples ended (SampleDistances).
    const size_t size = (*rows)[a].to_samples.size();
    if (size <= static_cast<size_t>(a) || size > static_cast<size_t>(num_samples)) {
      return absl::InvalidArgumentError(absl::StrFormat("row of sample %d has the wrong size", a));
    }
  }
  return absl::OkStatus();
}

// d(a, b) between samples, from rows sorted by sample. The two propagations
// agree to rounding; the shorter is kept (both are lengths of real paths), so
// the matrix is symmetric. A row carried from an earlier round of a
// target-error build has no entries for the samples added after it: their
// own rows have it (every row reaches its own sample, SortAndCheckRows).
class SampleDistances {
 public:
  explicit SampleDistances(const std::vector<SampleRow>& rows) : rows_(&rows) {}

  double operator()(int32_t a, int32_t b) const {
    const std::vector<double>& from_a = (*rows_)[a].to_samples;
    const std::vector<double>& from_b = (*rows_)[b].to_samples;
    if (static_cast<size_t>(b) >= from_a.size()) return from_b[a];
    if (static_cast<size_t>(a) >= from_b.size()) return from_a[b];
    return std::min(from_a[b], from_b[a]);
  }

  // The index's m x m matrix, row-major, 0 on the diagonal.
  std::vector<float> Matrix() const {
    const size_t m = rows_->size();
    std::vector<float> matrix(m * m);
    for (size_t a = 0; a < m; ++a) {
      for (size_t b = 0; b < m; ++b) {
        matrix[a * m + b] = a == b ? 0.0f : static_cast<float>((*this)(a, b));
      }
    }
    return matrix;
  }

 private:
  const std::vector<SampleRow>* rows_;
};

// d(v, b) for every vertex v and every sample b of v's cell or of a cell
// next to it, gathered from the rows' to_cell_vertices.
class CellDistances {
 public:
  // `neighbors`: plan.SampleNeighbors(); `rows` sorted by sample. Both must
  // outlive the result. Errors: InvalidArgument for a row with the wrong
  // number of cell distances.
  static absl::StatusOr<CellDistances> FromRows(const Plan& plan,
                                                const std::vector<std::vector<int32_t>>& neighbors,
                                                const std::vector<SampleRow>& rows) {
    CellDistances out(plan, neighbors);
    for (int32_t a = 0; a < plan.num_samples(); ++a) {
      const std::vector<int32_t> vertices = CellVertices(plan, neighbors[a], a);
      if (vertices.size() != rows[a].to_cell_vertices.size()) {
        return absl::InvalidArgumentError(
            absl::StrFormat("row of sample %d has %d cell distances, expected %d", a,
                            rows[a].to_cell_vertices.size(), vertices.size()));
      }
      for (size_t k = 0; k < vertices.size(); ++k) {
        const int32_t slot = out.Slot(vertices[k], a);
        if (slot != kNone) out.slots_[slot] = rows[a].to_cell_vertices[k];
      }
    }
    return out;
  }

  // `b` must be v's cell or one next to it.
  double operator()(int32_t v, int32_t b) const { return slots_[Slot(v, b)]; }

 private:
  // One slot per vertex for its own cell's sample, then one per neighbour.
  CellDistances(const Plan& plan, const std::vector<std::vector<int32_t>>& neighbors)
      : plan_(&plan), neighbors_(&neighbors) {
    const int32_t nv = static_cast<int32_t>(plan.nearest.size());
    slot_offset_.assign(nv + 1, 0);
    for (int32_t v = 0; v < nv; ++v) {
      const int32_t a = plan.nearest[v];
      slot_offset_[v + 1] = slot_offset_[v] + (a == kNone ? 0 : 1 + neighbors[a].size());
    }
    slots_.assign(slot_offset_[nv], geodesic::kInfinity);
  }

  // The slot of d(v, b), or kNone when b is neither v's cell nor next to it.
  int32_t Slot(int32_t v, int32_t b) const {
    const int32_t a = plan_->nearest[v];
    if (b == a) return slot_offset_[v];
    const auto& list = (*neighbors_)[a];
    const auto it = std::lower_bound(list.begin(), list.end(), b);
    if (it == list.end() || *it != b) return kNone;
    return slot_offset_[v] + 1 + static_cast<int32_t>(it - list.begin());
  }

  const Plan* plan_;
  const std::vector<std::vector<int32_t>>* neighbors_;
  std::vector<int32_t> slot_offset_;
  std::vector<double> slots_;
};

}  // namespace

void AddMeshAndTriangulation(const Mesh& mesh, const Plan& plan, index::IndexData* data) {
  data->builder_version = kBuilderVersion;
  data->mesh_hash = plan.mesh_hash;
  data->params.requested_samples = plan.requested_samples;
  data->params.num_samples = plan.num_samples();
  data->params.seed = plan.seed;
  data->params.samples_added_by_repair = plan.repair.samples_added;
  data->positions = FlatPositions(mesh);
  data->faces = FlatFaces(mesh);
  for (int32_t h = 0; h < mesh.num_halfedges(); ++h) data->twins.push_back(mesh.Twin(h));
  data->samples = plan.samples;
  for (size_t t = 0; t < plan.triangles.size(); ++t) {
    index::GeodesicTriangle tri;
    for (int i = 0; i < 3; ++i) {
      tri.corner[i] = plan.triangles[t][i];
      tri.neighbor[i] = plan.neighbors[t][i];
    }
    data->triangles.push_back(tri);
  }
  index::BuildFaceBvh(data->positions, data->faces, &data->bvh_nodes, &data->bvh_faces);
}

namespace {

// The summary's figures but merge_seconds.
void Summarize(const Mesh& mesh, const Plan& plan, const SampleDistances& sample_distance,
               const AssignmentCounts& counts, BuildSummary* summary) {
  double longest = 0;
  for (const auto& t : plan.triangles) {
    for (int i = 0; i < 3; ++i) longest = std::max(longest, sample_distance(t[i], t[(i + 1) % 3]));
  }
  summary->sampling_seconds = plan.sampling_seconds;
  summary->triangulation_seconds = plan.triangulation_seconds;
  summary->requested_samples = plan.requested_samples;
  summary->num_samples = plan.num_samples();
  summary->repair = plan.repair.Summary();
  summary->euler_samples = plan.repair.euler_samples;
  summary->num_triangles = static_cast<int32_t>(plan.triangles.size());
  summary->referenced_vertices = counts.referenced;
  summary->unassigned_vertices = counts.unassigned;
  summary->share_outside =
      counts.referenced > 0 ? static_cast<double>(counts.outside) / counts.referenced : 0;
  summary->longest_edge = longest;
  summary->geodesic_edges = plan.edge_stats.count;
  summary->edge_crossings_found = plan.repair.crossings_found;
  summary->edge_length_total = plan.edge_stats.total_length;
  summary->edge_length_max = plan.edge_stats.longest;
  summary->edge_length_error = plan.edge_stats.max_relative_error;
  summary->bbox_diagonal = mesh.BoundingBoxDiagonal();
}

// How far a carried row's propagation must go to reach every vertex of its
// sample's cell and of the neighbouring cells: d(a, c) + the radius of cell
// c, the largest over c = a and its neighbours. d(a, c) comes from a's
// carried row when it has it; otherwise (c came after it) the two cells
// touch across a mesh edge, so d(a, c) <= radius(a) + that edge + radius(c).
class CarriedCellReach {
 public:
  CarriedCellReach(const Mesh& mesh, const Plan& plan,
                   const std::vector<std::vector<int32_t>>& neighbors, std::span<SampleRow> carried)
      : plan_(plan), neighbors_(neighbors), carried_(carried) {
    if (carried.empty()) return;
    for (int32_t h = 0; h < mesh.num_halfedges(); ++h) {
      longest_edge_ = std::max(longest_edge_, mesh.Length(h));
    }
  }

  // 0 when there is no bound (a plan without cell radii).
  double Radius(int32_t a) const {
    if (plan_.cell_radius.size() != static_cast<size_t>(plan_.num_samples())) return 0;
    const std::vector<double>& row = carried_[a].to_samples;
    const double own = plan_.cell_radius[a];
    double reach = own;
    for (int32_t c : neighbors_[a]) {
      const double to_c =
          static_cast<size_t>(c) < row.size() ? row[c] : own + longest_edge_ + plan_.cell_radius[c];
      reach = std::max(reach, to_c + plan_.cell_radius[c]);
    }
    // A margin for rounding: the check after the propagation decides.
    return reach * (1 + 1e-6) + 1e-9 * longest_edge_;
  }

 private:
  const Plan& plan_;
  const std::vector<std::vector<int32_t>>& neighbors_;
  std::span<SampleRow> carried_;
  double longest_edge_ = 0;
};

// Samples the repair may add beyond 4m + 64 for the mesh's topology: a
// closed component needs 4 samples at least (a tetrahedron), and each handle
// or boundary loop (2 - chi of its component, a scan's slits and tiny handles
// among them) a ring of cells round it: 2 to 3.2 samples a non-manifold edge
// cut on clustered scans (core/mesh/README.md#topology-the-samples-miss); 16 each
// leaves room.
int64_t TopologyBudget(const Mesh& mesh) {
  std::vector<int64_t> chi(mesh.num_components(), 0);
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.IsReferenced(v)) ++chi[mesh.VertexComponent(v)];
  }
  for (int32_t h = 0; h < mesh.num_halfedges(); ++h) {
    if (mesh.Twin(h) == kNone || mesh.Twin(h) > h) --chi[mesh.FaceComponent(Mesh::FaceOf(h))];
  }
  for (int32_t f = 0; f < mesh.num_faces(); ++f) ++chi[mesh.FaceComponent(f)];
  int64_t budget = 0;
  for (int64_t c : chi) budget += 4 + 16 * std::max<int64_t>(0, 2 - c);
  return budget;
}

// MakePlan's second half, shared with ExtendPlan: the repair of `set` into
// a valid triangulation, and the plan made of both.
absl::Status RepairIntoPlan(const Mesh& mesh, sampling::SampleSet set, const BuildOptions& options,
                            Plan* plan) {
  plan->mesh_hash = index::MeshHash(FlatPositions(mesh), FlatFaces(mesh));
  plan->requested_samples = options.num_samples;
  plan->seed = options.seed;
  const auto start = std::chrono::steady_clock::now();
  if (options.progress) options.progress({"repair", 0, 1});
  triangulation::RepairOptions repair;
  repair.max_rounds = options.max_repair_rounds;
  repair.max_samples = static_cast<int32_t>(std::min<int64_t>(
      std::max<int64_t>(4 * int64_t{options.num_samples} + 64, 256) + TopologyBudget(mesh),
      mesh.num_vertices()));
  repair.input_vertex_ids = options.input_vertex_ids;
  repair.check_edges = options.check_edges;
  repair.threads = ThreadCount(options);
  GEODEX_ASSIGN_OR_RETURN(triangulation::DualComplex dual,
                          triangulation::RepairTriangulation(mesh, &set, repair, &plan->repair));
  plan->triangulation_seconds = SecondsSince(start);
  if (options.progress) options.progress({"repair", 1, 1});
  plan->cell_radius.assign(set.samples.size(), 0.0);
  for (size_t v = 0; v < set.nearest.size(); ++v) {
    const int32_t a = set.nearest[v];
    if (a != kNone) plan->cell_radius[a] = std::max(plan->cell_radius[a], set.distance[v]);
  }
  plan->samples = std::move(set.samples);
  plan->nearest = std::move(set.nearest);
  plan->triangles = std::move(dual.triangles);
  plan->neighbors = std::move(dual.neighbors);
  plan->edges = std::move(dual.edges);
  plan->edge_stats = triangulation::SummarizeEdges(plan->edges);
  return absl::OkStatus();
}

}  // namespace

std::string BuildSummary::ToText() const {
  std::string out = absl::StrFormat(
      "requested_samples = %d\nsamples = %d\nrepair = %s\ntriangles = %d\n"
      "referenced_vertices = %d\nunassigned_vertices = %d\nshare_outside_triangle = %.6g\n"
      "longest_edge = %.9g\nbbox_diagonal = %.9g\ngeodesic_edges = %d\n"
      "edge_crossings_found = %d\ngeodesic_edge_length_total = %.9g\n"
      "geodesic_edge_length_max = %.9g\ngeodesic_edge_length_error = %.3g\n",
      requested_samples, num_samples, repair, num_triangles, referenced_vertices,
      unassigned_vertices, share_outside, longest_edge, bbox_diagonal, geodesic_edges,
      edge_crossings_found, edge_length_total, edge_length_max, edge_length_error);
  // Only when there are any, so that an index of a mesh whose samples saw its
  // topology keeps its bytes.
  if (!euler_samples.empty()) {
    absl::StrAppend(&out, "repair_euler_samples = ", absl::StrJoin(euler_samples, " "), "\n");
  }
  return out;
}

absl::StatusOr<Plan> MakePlan(const Mesh& mesh, const BuildOptions& options) {
  Plan plan;
  const auto start = std::chrono::steady_clock::now();
  if (options.progress) options.progress({"sampling", 0, options.num_samples});
  GEODEX_ASSIGN_OR_RETURN(sampling::SampleSet set,
                          sampling::FarthestPointSampling(mesh, options.num_samples, options.seed,
                                                          options.spacing_weight));
  plan.sampling_seconds = SecondsSince(start);
  if (options.progress) options.progress({"sampling", options.num_samples, options.num_samples});
  GEODEX_RETURN_IF_ERROR(RepairIntoPlan(mesh, std::move(set), options, &plan));
  return plan;
}

absl::StatusOr<Plan> ExtendPlan(const Mesh& mesh, std::span<const int32_t> previous,
                                const BuildOptions& options) {
  const int32_t nv = mesh.num_vertices();
  if (previous.empty() || static_cast<int32_t>(previous.size()) > options.num_samples) {
    return absl::InvalidArgumentError(
        absl::StrFormat("cannot grow %d samples to %d", previous.size(), options.num_samples));
  }
  std::vector<uint8_t> taken(nv, 0);
  for (int32_t v : previous) {
    if (v < 0 || v >= nv || !mesh.IsReferenced(v) || taken[v]) {
      return absl::InvalidArgumentError(
          absl::StrFormat("vertex %d cannot be a carried sample of this mesh", v));
    }
    taken[v] = 1;
  }
  Plan plan;
  const auto start = std::chrono::steady_clock::now();
  if (options.progress) options.progress({"sampling", 0, options.num_samples});
  // The Voronoi diagram of the carried samples on this mesh (one
  // propagation from all of them), then farthest-point sampling goes on
  // from there exactly as FarthestPointSampling would.
  geodesic::VertexGeodesicSolver solver(mesh);
  GEODEX_RETURN_IF_ERROR(solver.Propagate(previous));
  sampling::SampleSet set;
  set.samples.assign(previous.begin(), previous.end());
  set.distance = solver.VertexDistances();
  set.nearest.resize(nv);
  for (int32_t v = 0; v < nv; ++v) set.nearest[v] = solver.NearestSource(v);
  for (size_t k = 0; k < previous.size(); ++k) {
    set.distance[previous[k]] = 0;
    set.nearest[previous[k]] = static_cast<int32_t>(k);
  }
  if (!options.spacing_weight.empty() && options.spacing_weight.size() != static_cast<size_t>(nv)) {
    return absl::InvalidArgumentError("spacing weights of the wrong size");
  }
  while (static_cast<int32_t>(set.samples.size()) < options.num_samples) {
    const int32_t next = sampling::FarthestVertex(mesh, set, {}, options.spacing_weight);
    if (next == kNone) break;  // every vertex is a sample
    GEODEX_RETURN_IF_ERROR(sampling::AddSample(solver, next, &set));
  }
  plan.sampling_seconds = SecondsSince(start);
  if (options.progress) options.progress({"sampling", options.num_samples, options.num_samples});
  GEODEX_RETURN_IF_ERROR(RepairIntoPlan(mesh, std::move(set), options, &plan));
  return plan;
}

namespace {

// The sample ids asked for and the carried rows, checked against a plan of
// m samples.
absl::Status CheckRowRequest(int32_t m, std::span<const int32_t> sample_ids,
                             std::span<const SampleRow> carried) {
  for (int32_t id : sample_ids) {
    if (id < 0 || id >= m) {
      return absl::InvalidArgumentError(absl::StrFormat("sample %d out of range [0, %d)", id, m));
    }
  }
  if (static_cast<int32_t>(carried.size()) > m) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%d carried rows for a plan of %d samples", carried.size(), m));
  }
  for (size_t a = 0; a < carried.size(); ++a) {
    if (carried[a].to_samples.size() <= a ||
        carried[a].to_samples.size() > static_cast<size_t>(m)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("the carried row of sample %d has the wrong size", a));
    }
  }
  return absl::OkStatus();
}

// What every thread of ComputeRows reads.
struct RowContext {
  const Mesh& mesh;
  const Plan& plan;
  const std::vector<std::vector<int32_t>>& neighbors;
  const CarriedCellReach& reach;
  std::span<SampleRow> carried;
  const index::CoarseSurface* coarse;
  // The samples as points of the coarse surface (empty without one).
  const std::vector<SurfacePoint>& sample_points;
};

// One thread of ComputeRows: its propagation engine and scratch space.
class RowWorker {
 public:
  // Rows need vertex distances only: the wavefront engine, whose memory
  // follows the front rather than the whole propagation.
  explicit RowWorker(const RowContext& c)
      : c_(c), solver_(c.coarse != nullptr ? c.coarse->mesh : c.mesh) {}

  // Fills `row`, sample a's.
  absl::Status Row(int32_t a, SampleRow& row) {
    row.sample = a;
    const std::vector<int32_t> cell_vertices = CellVertices(c_.plan, c_.neighbors[a], a);
    if (a < static_cast<int32_t>(c_.carried.size())) {
      GEODEX_RETURN_IF_ERROR(CarriedRow(a, cell_vertices, row));
    }
    if (row.to_samples.empty() || row.to_cell_vertices.size() != cell_vertices.size()) {
      GEODEX_RETURN_IF_ERROR(FullRow(a, cell_vertices, row));
    }
    return absl::OkStatus();
  }

 private:
  // From sample a, with `targets_` laid out as `first_cell` points before
  // the cell vertices' (coarse) or none (split mesh).
  absl::Status Propagate(int32_t a, geodesic::VertexGeodesicOptions propagation) {
    if (c_.coarse == nullptr) return solver_.Propagate({c_.plan.samples[a]}, propagation);
    propagation.targets = targets_;
    return solver_.Propagate({c_.sample_points[a]}, propagation);
  }
  // After Propagate: the distance to vertex v of `mesh`, target k of the
  // coarse propagation; +inf where it did not reach.
  double Distance(int32_t v, size_t k) const {
    return c_.coarse == nullptr ? solver_.VertexDistance(v) : solver_.TargetDistance(k);
  }
  void CellTargets(std::span<const int32_t> cell_vertices, bool with_samples) {
    targets_.clear();
    if (c_.coarse == nullptr) return;
    if (with_samples) targets_ = c_.sample_points;
    for (int32_t v : cell_vertices) targets_.push_back(c_.coarse->points[v]);
  }

  // The carried row of sample a, and its cell vertices' distances when a
  // propagation bounded by the reach of its cell gets to them all.
  absl::Status CarriedRow(int32_t a, const std::vector<int32_t>& cell_vertices, SampleRow& row) {
    // Exact below the cap (vertices the propagation did not reach
    // sooner keep it: +inf at the targets, NearestSource kNone at
    // vertices); a full propagation when a cell vertex lies beyond it
    // after all.
    const double radius = c_.reach.Radius(a);
    row.to_samples = std::move(c_.carried[a].to_samples);
    if (radius <= 0) return absl::OkStatus();
    cap_.assign(solver_.mesh().num_vertices(), radius);
    geodesic::VertexGeodesicOptions bounded;
    bounded.initial_distance = cap_;
    CellTargets(cell_vertices, false);
    GEODEX_RETURN_IF_ERROR(Propagate(a, bounded));
    bool reached = true;
    for (size_t j = 0; j < cell_vertices.size(); ++j) {
      reached &= c_.coarse == nullptr ? solver_.NearestSource(cell_vertices[j]) == 0
                                      : std::isfinite(solver_.TargetDistance(j));
    }
    if (reached) {
      for (size_t j = 0; j < cell_vertices.size(); ++j)
        row.to_cell_vertices.push_back(Distance(cell_vertices[j], j));
    }
    return absl::OkStatus();
  }

  // The cell vertices' distances, and the samples' when the row has none,
  // from one propagation without a bound.
  absl::Status FullRow(int32_t a, const std::vector<int32_t>& cell_vertices, SampleRow& row) {
    const int32_t m = c_.plan.num_samples();
    row.to_cell_vertices.clear();
    const bool with_samples = row.to_samples.empty();
    CellTargets(cell_vertices, with_samples);
    GEODEX_RETURN_IF_ERROR(Propagate(a, {}));
    const size_t first_cell = c_.coarse != nullptr && with_samples ? m : 0;
    if (with_samples) {
      row.to_samples.resize(m);
      for (int32_t b = 0; b < m; ++b) row.to_samples[b] = Distance(c_.plan.samples[b], b);
      row.to_samples[a] = 0;  // a target at the source, whatever its rounding
    }
    for (size_t j = 0; j < cell_vertices.size(); ++j) {
      row.to_cell_vertices.push_back(Distance(cell_vertices[j], first_cell + j));
    }
    return absl::OkStatus();
  }

  const RowContext& c_;
  geodesic::VertexGeodesicSolver solver_;
  std::vector<double> cap_;
  std::vector<SurfacePoint> targets_;
};

}  // namespace

absl::StatusOr<std::vector<SampleRow>> ComputeRows(const Mesh& mesh, const Plan& plan,
                                                   std::span<const int32_t> sample_ids,
                                                   const BuildOptions& options,
                                                   std::span<SampleRow> carried,
                                                   const index::CoarseSurface* coarse) {
  const int32_t m = plan.num_samples();
  GEODEX_RETURN_IF_ERROR(CheckRowRequest(m, sample_ids, carried));
  const std::vector<std::vector<int32_t>> neighbors = plan.SampleNeighbors();
  const CarriedCellReach reach(mesh, plan, neighbors, carried);
  std::vector<SampleRow> rows(sample_ids.size());
  std::atomic<size_t> next{0};
  std::atomic<int64_t> done{0};
  std::mutex progress_mutex;
  const int threads = std::min<int>(ThreadCount(options), std::max<size_t>(1, sample_ids.size()));
  std::vector<absl::Status> errors(threads);
  if (coarse != nullptr && static_cast<int32_t>(coarse->points.size()) != mesh.num_vertices()) {
    return absl::InvalidArgumentError("the coarse surface is not of this mesh");
  }
  // On a split mesh the rows propagate on the surface before the split
  // (index::CoarseSurface): the same distances over several times fewer vertices,
  // read at the samples and cell vertices as target points.
  std::vector<SurfacePoint> sample_points;
  if (coarse != nullptr) {
    for (int32_t b = 0; b < m; ++b) sample_points.push_back(coarse->points[plan.samples[b]]);
  }
  const RowContext context{mesh, plan, neighbors, reach, carried, coarse, sample_points};
  auto worker = [&](int id) {
    RowWorker row_worker(context);
    for (size_t k; (k = next.fetch_add(1)) < sample_ids.size();) {
      if (absl::Status status = row_worker.Row(sample_ids[k], rows[k]); !status.ok()) {
        errors[id] = status;
        return;
      }
      const int64_t finished = ++done;
      if (options.progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        options.progress({"rows", finished, static_cast<int64_t>(sample_ids.size())});
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker, t);
  for (std::thread& t : pool) t.join();
  for (const absl::Status& status : errors) GEODEX_RETURN_IF_ERROR(status);
  return rows;
}

absl::StatusOr<index::IndexData> Merge(const Mesh& mesh, const Plan& plan,
                                       std::vector<SampleRow> rows, BuildSummary* summary) {
  return MergeKeepingRows(mesh, plan, &rows, summary);
}

absl::StatusOr<index::IndexData> MergeKeepingRows(const Mesh& mesh, const Plan& plan,
                                                  std::vector<SampleRow>* rows,
                                                  BuildSummary* summary) {
  const auto start = std::chrono::steady_clock::now();
  GEODEX_RETURN_IF_ERROR(SortAndCheckRows(plan.num_samples(), rows));
  const std::vector<std::vector<int32_t>> neighbors = plan.SampleNeighbors();
  const SampleDistances sample_distance(*rows);
  GEODEX_ASSIGN_OR_RETURN(const CellDistances vertex_distance,
                          CellDistances::FromRows(plan, neighbors, *rows));
  index::IndexData data;
  data.sample_distances = sample_distance.Matrix();
  // Stored once, in 24-bit codes: 3/8 of the full float32 matrix (sample_matrix.h).
  data.sample_matrix = index::MatrixLayout::kCoded;
  const AssignmentCounts counts =
      AssignVerticesToTriangles(mesh, plan, sample_distance, vertex_distance, &data.vertices);
  AddMeshAndTriangulation(mesh, plan, &data);
  Summarize(mesh, plan, sample_distance, counts, summary);
  summary->merge_seconds = SecondsSince(start);
  if (counts.unassigned > 0) {
    return absl::InternalError(absl::StrFormat(
        "%d referenced vertices have no geodesic triangle (a cell without triangles)",
        counts.unassigned));
  }
  data.report = summary->ToText();
  return data;
}

absl::StatusOr<index::IndexData> BuildIndex(const Mesh& mesh, const BuildOptions& options,
                                            BuildSummary* summary) {
  GEODEX_ASSIGN_OR_RETURN(const Plan plan, MakePlan(mesh, options));
  return BuildIndexFromPlan(mesh, plan, options, summary);
}

absl::StatusOr<index::IndexData> BuildIndexFromPlan(const Mesh& mesh, const Plan& plan,
                                                    const BuildOptions& options,
                                                    BuildSummary* summary,
                                                    const index::CoarseSurface* coarse) {
  std::vector<int32_t> all(plan.num_samples());
  for (int32_t a = 0; a < plan.num_samples(); ++a) all[a] = a;
  const auto start = std::chrono::steady_clock::now();
  GEODEX_ASSIGN_OR_RETURN(std::vector<SampleRow> rows,
                          ComputeRows(mesh, plan, all, options, {}, coarse));
  const double rows_seconds = SecondsSince(start);
  GEODEX_ASSIGN_OR_RETURN(index::IndexData data, Merge(mesh, plan, std::move(rows), summary));
  summary->rows_seconds = rows_seconds;
  return data;
}

absl::StatusOr<index::IndexData> BuildPreparedIndex(const PreparedMesh& prepared,
                                                    const BuildOptions& options,
                                                    BuildSummary* summary) {
  GEODEX_ASSIGN_OR_RETURN(const std::optional<index::CoarseSurface> coarse,
                          CoarseSurfaceOf(prepared.mesh, prepared.record));
  GEODEX_ASSIGN_OR_RETURN(const Plan plan, MakePlan(prepared.mesh, options));
  GEODEX_ASSIGN_OR_RETURN(index::IndexData data,
                          BuildIndexFromPlan(prepared.mesh, plan, options, summary,
                                             coarse ? &*coarse : nullptr));
  AddRepair(prepared.record, &data);
  return data;
}

}  // namespace geodex::builder
