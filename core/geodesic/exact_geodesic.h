#pragma once

// Exact polyhedral geodesics by window propagation.
//
// The algorithm is the improved Chen-Han method (ICH) of Xin & Wang,
// "Improving Chen and Han's algorithm on the discrete geodesic problem",
// ACM TOG 28(4), 2009: windows (intervals of an edge visible from one
// unfolded pseudo-source) are propagated face by face in order of their
// distance from the source; saddle and boundary vertices become pseudo-sources
// of their own; and a window is discarded as soon as one of the three vertices
// of the face it enters provably offers a shorter path to every point of it
// (the ICH filter). The result is exact up to floating-point rounding.
//
// Example:
//   geodex::geodesic::ExactGeodesicSolver solver(mesh);
//   GEODEX_RETURN_IF_ERROR(solver.Propagate({source}));
//   double d = solver.VertexDistance(v);            // +inf if unreachable
//   double e = solver.DistanceAt(point);            // any surface point
//   auto path = solver.PathTo(point);               // polyline back to the source
//
// A propagation may be confined to a region of faces (GeodesicOptions::
// face_region): it then runs as on the sub-mesh those faces make, and keeps
// the windows that reach the region's border for bounds on the paths that
// leave it (core/geodesic/confined_geodesic.h). A propagation resets only the
// state the one before it touched, so a small one costs little on a large
// mesh.
//
// Thread safety: a solver holds per-propagation state and is not thread-safe;
// use one solver per thread. Any number of solvers may share one const Mesh.

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <span>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/geodesic/radix_heap.h"
#include "core/geodesic/window_geometry.h"
#include "core/mesh/mesh.h"

namespace geodex::geodesic {

using mesh::Mesh;
using mesh::SurfacePoint;

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct GeodesicOptions {
  // Propagation stops once every unexplored point is farther than this from
  // all sources. Vertices beyond it keep +inf (or their initial distance).
  double stop_radius = kInfinity;
  // If non-empty, propagation stops as soon as the distances to all of these
  // vertices are final. Distances elsewhere are then upper bounds.
  std::vector<int32_t> stop_vertices;
  // Likewise for surface points.
  std::vector<SurfacePoint> stop_points;
  // Optional per-vertex distances from earlier propagations (size
  // num_vertices). The propagation only explores where it gets closer than
  // these; afterwards VertexDistance(v) = min(initial, new). Vertices that keep
  // their initial distance report NearestSource kNone and have no path.
  std::span<const double> initial_distance;
  // Safety net against pathological inputs: ResourceExhausted past this many
  // windows. 0 means 400 per half-edge plus 10^6.
  int64_t max_windows = 0;
  // When > 0: ResourceExhausted as soon as more than this many vertices have
  // a distance (ReachedVertices()), so that a caller answering a bounded
  // request stops paying once it is over its budget.
  int64_t max_vertices = 0;
  // If non-empty (one entry per face), the propagation is confined to the
  // region R of faces f with face_region[f] != 0, as if the other faces did
  // not exist: distances are those along paths inside R, and a vertex of R
  // with a face outside R is a boundary vertex of R (a pseudo-source in every
  // direction, when R's angle there exceeds pi or R's faces round it make
  // more than one fan). Every source must lie in a face of R. Windows that reach an
  // edge of R whose other face lies outside R stop there and are kept as
  // BorderWindows(). Read during Propagate only.
  std::span<const uint8_t> face_region;
  // If finite: an upper bound on the distance to the point `prune_point`
  // (e.g. the length of a path to it). Windows and vertices every path
  // through which to that point is longer than this, by the straight line
  // from them to it, are not propagated: the point's distance stays exact
  // (and so does every distance d(x) with d(x) + |x - prune_point| below
  // the bound), others may be left larger. Focuses a propagation between two
  // points on the ellipsoid round them.
  double prune_length = kInfinity;
  mesh::Vec3 prune_point = mesh::Vec3::Zero();
};

struct GeodesicStats {
  int64_t windows_created = 0;
  int64_t windows_propagated = 0;
  int64_t vertex_events = 0;
};

class ExactGeodesicSolver {
 public:
  // A window that reached the border of a face_region: the interval [b0,b1]
  // of the edge of half-edge `h` (h's face lies outside the region, its
  // twin's inside), measured from Origin(h), lit by the pseudo-source
  // (sx,sy), sy <= 0, unfolded into h's frame (origin at Origin(h), x along
  // the edge, the outside face at y > 0) at distance `sigma` from the source.
  // Every point x of the interval is reached inside the region by a path of
  // length sigma + |(sx,sy) - (x,0)|. Kept before any filter, so that the
  // border windows and the distances of the region's vertices between them
  // give the exact in-region distance of every point of the border edges
  // closer than SettledBelow().
  struct BorderWindow {
    int32_t h;
    double b0, b1;
    double sx, sy;
    double sigma;
  };

  // `mesh` must outlive the solver.
  explicit ExactGeodesicSolver(const Mesh& mesh);

  // Runs a propagation from `sources` (at least one). Each source is a surface
  // point; sources that coincide are allowed. Errors: InvalidArgument /
  // OutOfRange for an invalid source (see mesh::ValidateSurfacePoint) or an
  // initial_distance of the wrong size; ResourceExhausted past max_windows or
  // max_vertices.
  // Results of an earlier propagation are discarded.
  absl::Status Propagate(std::span<const SurfacePoint> sources,
                         const GeodesicOptions& options = {});
  absl::Status Propagate(std::initializer_list<SurfacePoint> sources,
                         const GeodesicOptions& options = {}) {
    return Propagate(std::span<const SurfacePoint>(sources.begin(), sources.size()), options);
  }

  // Distance from the nearest source to vertex `v`; +inf when unreachable (a
  // different connected component, or beyond the stop radius).
  double VertexDistance(int32_t v) const { return dist_[v]; }
  const std::vector<double>& VertexDistances() const { return dist_; }
  // Index (into the sources given to Propagate) of the source nearest to `v`,
  // or mesh::kNone when unreachable: the geodesic Voronoi diagram at vertices.
  int32_t NearestSource(int32_t v) const { return nearest_[v]; }
  const std::vector<int32_t>& NearestSources() const { return nearest_; }
  // The vertices the last propagation gave a distance, in the order it
  // reached them, each once: without initial_distance, exactly those whose
  // distance is finite. With a stop radius they are the vertices within it
  // and a ring beyond (upper bounds there); reading them costs what the
  // propagation reached, not O(n).
  std::span<const int32_t> ReachedVertices() const { return touched_vertices_; }

  // Exact distance at any surface point (the point must be valid). +inf when
  // unreachable.
  double DistanceAt(const SurfacePoint& p) const;

  // Exact geodesic from `p` back to its nearest source, as surface points: `p`
  // first, then every edge crossing and vertex, the source last. Each point is
  // expressed in a face that contains it. Errors: InvalidArgument for a bad
  // point, NotFound when `p` is unreachable, FailedPrecondition when the path
  // runs into a vertex whose distance came from `initial_distance`.
  absl::StatusOr<std::vector<SurfacePoint>> PathTo(const SurfacePoint& p) const;

  // The windows of the last propagation that reached the border of its
  // face_region (none without one).
  std::span<const BorderWindow> BorderWindows() const { return border_windows_; }
  // A distance below which every result of the last propagation is final:
  // +inf when it ran to the end, else the distance of the front where a stop
  // radius or the stop targets ended it (at least their distances).
  double SettledBelow() const { return settled_below_; }

  const GeodesicStats& stats() const { return stats_; }
  const Mesh& mesh() const { return mesh_; }

 private:
  // A window lies on the edge of half-edge `h` and looks into FaceOf(h). The
  // interval [b0,b1] is measured from Origin(h); the pseudo-source (sx,sy),
  // sy <= 0, is unfolded into h's frame, at geodesic distance `sigma` from
  // the source. Aligned to a cache line, so that reading one (prefetched as
  // it nears the front of the queue) costs one line.
  struct alignas(64) Window {
    double b0, b1;
    double sx, sy;
    double sigma;
    int32_t h;
    int32_t parent;  // window this one was propagated from, or kNone
    int32_t pseudo;  // pseudo-source vertex when parent == kNone, else kNone
    int32_t source;  // source index
    int32_t next_on_edge;
  };
  static_assert(sizeof(Window) == 64);
  // How a vertex got its distance, for path tracing.
  enum class Via : uint8_t { kNone, kInitial, kSource, kVertex, kWindow };
  struct VertexOrigin {
    Via via = Via::kNone;
    int32_t id = mesh::kNone;  // source index, vertex or window
  };
  struct SourceInFace {
    int32_t face;
    int32_t source;
    mesh::Vec3 position;
  };
  // Shortest path seen to the opposite vertex through a half-edge: its
  // distance and where it crosses the edge.
  struct Split {
    double dc = kInfinity;
    double x = 0;
  };
  struct Candidate {
    double distance = kInfinity;
    Via via = Via::kNone;
    int32_t id = mesh::kNone;
  };

  // Clears the state of the last propagation: only the entries it touched,
  // unless it started from initial distances.
  void Reset();
  // Records the first change of vertex v's state since Reset.
  void Touch(int32_t v) {
    if (dist_[v] == kInfinity) touched_vertices_.push_back(v);
  }
  bool InRegion(int32_t face) const { return region_.empty() || region_[face] != 0; }
  // Where v lies in the face region (kInsideRegion without one): inside
  // (all its faces in the region), or on the border, where it is a
  // pseudo-source when shortest paths in the region may bend round it
  // (reflex) and not otherwise (convex).
  static constexpr uint8_t kUnknown = 0, kInsideRegion = 1, kReflexBorder = 2, kConvexBorder = 3;
  uint8_t RegionBorderState(int32_t v);
  absl::Status AddSource(const SurfacePoint& p, int32_t source);
  void AddFaceSource(int32_t face, const std::array<double, 3>& w, int32_t source,
                     int32_t skip_halfedge);
  void EmitFromVertex(int32_t v);
  // Direction (angle around v, see .cc) of the path that gave v its distance,
  // or -1 when there is no single one.
  double BackAngle(int32_t v) const;
  void UpdateVertex(int32_t v, double d, int32_t source, Via via, int32_t id);
  void PushWindow(const Window& w);
  bool IsUseless(const Window& w) const;
  void PropagateWindow(int32_t index);
  double MinDistance(const Window& w) const;
  bool TargetsSettled(double key) const;
  double UpperBoundAt(const SurfacePoint& p) const;
  Candidate BestAt(const SurfacePoint& p) const;
  // 2D coordinates of a surface point in the frame of half-edge `h`, which must
  // belong to p.face.
  std::array<double, 2> InFrame(int32_t h, const SurfacePoint& p) const;

  const Mesh& mesh_;
  std::vector<HalfEdgeFrame> frame_;
  std::vector<double> corner_angle_;  // angle at Origin(h) in FaceOf(h)
  std::vector<uint8_t> emits_;        // saddle or boundary vertex: a pseudo-source
  std::vector<uint8_t> pinched_;      // an end of an edge of length 0

  std::vector<double> dist_;
  std::vector<int32_t> nearest_;
  std::vector<VertexOrigin> origin_;
  // Per vertex, RegionBorderState, or kUnknown before it is first needed.
  std::vector<uint8_t> region_border_;
  // What the last propagation touched: vertices whose dist_ became finite,
  // half-edges that got a window. full_reset_ when initial distances made
  // dist_ finite elsewhere too.
  std::vector<int32_t> touched_vertices_;
  std::vector<int32_t> touched_halfedges_;
  bool full_reset_ = true;
  std::span<const uint8_t> region_;
  std::vector<BorderWindow> border_windows_;
  double settled_below_ = kInfinity;
  // Reset clears windows_ and queue_ but keeps their memory: a reused solver
  // does not regrow them (on a fresh solver, growing windows_ takes a third
  // or more of the time of a large full propagation).
  std::vector<Window> windows_;
  std::vector<int32_t> edge_head_;  // first window on each half-edge
  std::vector<Split> split_;
  // Pending work by distance: window indices, and ~v for a vertex event of v.
  // A monotone queue suffices: whatever is pushed while an entry is processed
  // (the children of a window, the events of the vertices it reaches, the
  // windows a vertex emits) is at least as far from the sources as that
  // entry, up to rounding. A key that rounding puts below the last popped
  // one is clamped to it by the queue, i.e. popped next. That is harmless:
  // every window and vertex distance stands for an actual path, and the
  // filters only discard what such a path beats, so the result does not
  // depend on the pop order, only the amount of work does; and the clamped
  // keys differ from the exact ones by rounding only (measured: under 1% of
  // the pushes, by a few units in the last place). Pops report the keys as
  // pushed, so vertex events still match dist_ exactly and stop_radius and
  // the stop targets compare against true distances.
  RadixHeap<int32_t> queue_;
  std::vector<SourceInFace> face_sources_;
  std::vector<SurfacePoint> sources_;
  double stop_radius_ = kInfinity;
  double prune_length_ = kInfinity;
  mesh::Vec3 prune_point_ = mesh::Vec3::Zero();
  // Whether a window's paths may reach prune_point_ within prune_length_.
  bool MayReachPrunePoint(const Window& w) const;
  std::vector<int32_t> stop_vertices_;
  std::vector<SurfacePoint> stop_points_;
  int64_t max_windows_ = 0;
  int64_t max_vertices_ = 0;
  GeodesicStats stats_;
};

// One-shot convenience: exact distances at all vertices from `sources`.
absl::StatusOr<std::vector<double>> ExactGeodesicDistances(const Mesh& mesh,
                                                           std::span<const SurfacePoint> sources,
                                                           const GeodesicOptions& options = {});

}  // namespace geodex::geodesic
