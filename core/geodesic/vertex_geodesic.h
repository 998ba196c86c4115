#pragma once

// Exact geodesic distances at the vertices of a mesh, by vertex-ordered,
// triangle-oriented wavefront propagation: the method of Qin, Han, Yu, Yu &
// Zhang, "Fast and Exact Discrete Geodesic Computation Based on
// Triangle-Oriented Wavefront Propagation", ACM TOG 35(4), 2016 ("VTP").
//
// Why a second exact engine beside ExactGeodesicSolver: the builder needs, per
// sample, only the distances at the vertices, and it needs m of them.
// ExactGeodesicSolver keeps every window it ever made (DistanceAt and PathTo
// walk them back) and orders the windows one by one in a global queue. This
// solver
//   - keeps only the wavefront: a window lives on an edge until it is
//     propagated across the next face, then it is freed, so memory follows the
//     front, not the history;
//   - orders vertices, not windows: the nearest unsettled vertex is settled,
//     and then every list of windows on an edge that touches a settled vertex
//     is propagated across its face, a whole list at a time, in FIFO order;
//   - prunes a list as a whole: the window of the list that reaches the
//     face's third vertex C soonest splits the face ("one angle, two sides"),
//     and every other window of the list only continues on its side of that
//     path where the other side is provably reached sooner through it.
// Windows are also dropped when one of the face's vertices offers a shorter
// path to every point of them (the filter of Xin & Wang 2009).
// The result is exact up to rounding: the tests compare it with
// ExactGeodesicSolver on generated surfaces, and the shared meshes' test and
// geodesic_bench compare them on scans.
//
// Example:
//   geodex::geodesic::VertexGeodesicSolver solver(mesh);
//   GEODEX_RETURN_IF_ERROR(solver.Propagate({source_vertex}));
//   double d = solver.VertexDistance(v);  // +inf if unreachable
//
// Thread safety: a solver holds per-propagation state and is not thread-safe;
// use one per thread. Any number of solvers may share one const Mesh.

#include <array>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <vector>

#include "absl/status/status.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/geodesic/radix_heap.h"
#include "core/geodesic/window_geometry.h"
#include "core/mesh/mesh.h"

namespace geodex::geodesic {

using mesh::Vec3;

struct VertexGeodesicOptions {
  // Optional per-vertex distances from earlier propagations (size
  // num_vertices): the propagation only explores where it gets closer than
  // these, and afterwards VertexDistance(v) = min(initial, new). Vertices that
  // keep their initial distance report NearestSource kNone. This is how
  // farthest-point sampling adds one sample at a time in time proportional
  // to the new sample's cell, not to the mesh.
  std::span<const double> initial_distance;
  // Surface points whose exact distances are wanted as well (TargetDistance):
  // each is evaluated against every window that enters its face, and against
  // the face's corners, so they cost nothing like ExactGeodesicSolver's
  // stored windows.
  std::span<const SurfacePoint> targets;
  // A guard against pathological input: ResourceExhausted past this many
  // windows created. 0 means 400 per half-edge plus 10^6.
  int64_t max_windows = 0;
};

struct VertexGeodesicStats {
  int64_t windows_created = 0;
  int64_t lists_propagated = 0;
  // The most windows alive at once: the solver's window memory is this times
  // sizeof(Window) (48 bytes).
  int64_t peak_windows = 0;
  int64_t vertices_settled = 0;
};

class VertexGeodesicSolver {
 public:
  // `mesh` must outlive the solver.
  explicit VertexGeodesicSolver(const Mesh& mesh);

  // Distances from the nearest of `sources` (vertex ids, at least one;
  // repeats allowed) to every vertex. Errors: InvalidArgument for no sources,
  // for an unreferenced source vertex, or for an initial_distance of the
  // wrong size or with a negative or NaN entry; OutOfRange for an id past
  // the end; ResourceExhausted past options.max_windows. Results of an
  // earlier propagation are discarded.
  absl::Status Propagate(std::span<const int32_t> sources,
                         const VertexGeodesicOptions& options = {});
  absl::Status Propagate(std::initializer_list<int32_t> sources,
                         const VertexGeodesicOptions& options = {}) {
    return Propagate(std::span<const int32_t>(sources.begin(), sources.size()), options);
  }
  // The same from surface points (a vertex, a point on an edge or inside a
  // face). Errors as above, and those of mesh::ValidateSurfacePoint for the
  // sources and targets.
  absl::Status Propagate(std::span<const SurfacePoint> sources,
                         const VertexGeodesicOptions& options = {});
  absl::Status Propagate(std::initializer_list<SurfacePoint> sources,
                         const VertexGeodesicOptions& options = {}) {
    return Propagate(std::span<const SurfacePoint>(sources.begin(), sources.size()), options);
  }

  // Distance from the nearest source to vertex `v`; +inf when unreachable.
  double VertexDistance(int32_t v) const { return dist_[v]; }
  const std::vector<double>& VertexDistances() const { return dist_; }
  // Index (into the sources given) of the source nearest to `v`, or
  // mesh::kNone when unreachable.
  int32_t NearestSource(int32_t v) const { return nearest_[v]; }
  // Distance from the nearest source to options.targets[i] (+inf when
  // unreachable or, with initial distances, not improved on them).
  double TargetDistance(size_t i) const { return target_dist_[i]; }

  const VertexGeodesicStats& stats() const { return stats_; }
  const Mesh& mesh() const { return mesh_; }

 private:
  // A window on the edge of a half-edge h, looking into FaceOf(h): the
  // interval [b0,b1] from Origin(h), lit by the pseudo-source (sx,sy), sy <= 0,
  // unfolded into h's frame at geodesic distance sigma from the source.
  struct Window {
    double b0, b1;
    double sx, sy;
    double sigma;
    int32_t source;
    int32_t next;  // next window of the same list, or the free list
  };
  static_assert(sizeof(Window) == 48);
  // kFront: next to a settled vertex or reached by a path; kWoken: queued at
  // its initial distance by WakeEnd (otherwise like kFront).
  enum State : uint8_t { kOutside, kFront, kWoken, kInside };
  // A window of the list being propagated, and where its shortest route to
  // the face's third vertex crosses the edge.
  struct Pending {
    Window window;
    double crossing;  // the "separating point" of VTP, clamped to [b0,b1]
    double xc;        // where the ray from the pseudo-source through C crosses
  };

  enum class PairVerdict { kBoth, kFirstDominated, kSecondDominated };

  struct SourceInFace {
    int32_t face;
    int32_t source;
    Vec3 position;
  };

  void Reset();
  absl::Status Start(const VertexGeodesicOptions& options);
  absl::Status Run();
  void AddFaceSource(int32_t face, const std::array<double, 3>& w, int32_t source,
                     int32_t skip_halfedge);
  void EvaluateTargets(int32_t h);
  // 2D coordinates of a point of FaceOf(h) in the frame of half-edge h.
  std::array<double, 2> InFrame(int32_t h, const SurfacePoint& p) const;
  void FinishTargets();
  PairVerdict ComparePair(Window& w1, Window& w2) const;
  void PruneNeighbours();
  void Settle(int32_t v);
  void EmitFrom(int32_t v);
  void UpdateVertex(int32_t v, double d, int32_t source);
  void AddWindow(int32_t h, const Window& w);
  bool IsUseless(int32_t h, const Window& w) const;
  void Enqueue(int32_t h);
  void WakeEnd(int32_t v);
  void PropagateList(int32_t h);
  void PropagateChild(int32_t t, const ChildWindow& c, const Window& w);
  int32_t Allocate();
  void Free(int32_t k);

  const Mesh& mesh_;
  std::vector<HalfEdgeFrame> frame_;
  std::vector<uint8_t> emits_;  // saddle or boundary vertex: a pseudo-source

  std::vector<double> dist_;
  std::vector<int32_t> nearest_;
  std::vector<State> state_;
  RadixHeap<int32_t> vertex_queue_;
  // Windows: a pool with a free list; head_[h] is the list on half-edge h.
  std::vector<Window> pool_;
  int32_t free_ = mesh::kNone;
  int64_t live_ = 0;
  std::vector<int32_t> head_;
  // Lists waiting to be propagated (FIFO), each at most once.
  std::vector<int32_t> fifo_;
  std::vector<uint8_t> queued_;
  std::vector<Pending> pending_;
  // Targets: for each face holding some, [target_begin_[f], next face's) in
  // target_order_ (indices into targets_); -1 elsewhere.
  std::vector<SurfacePoint> targets_;
  std::vector<double> target_dist_;
  std::vector<int32_t> target_order_;
  std::vector<int32_t> target_begin_;  // per face, or -1
  std::vector<int32_t> target_faces_;  // faces with targets, to reset target_begin_
  std::vector<SourceInFace> face_sources_;
  int64_t max_windows_ = 0;
  VertexGeodesicStats stats_;
};

}  // namespace geodex::geodesic
