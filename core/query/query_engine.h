#pragma once

// Constant-time approximate geodesic queries over a loaded index (Xin, Ying
// & He 2012, §5): distances between any two surface points, geodesic paths
// by tracing the gradient of the approximate distance field (§6.2), distance
// fields from several sources (§6.2), and point location.
//
// How a distance is answered. Each query point is first "lifted" to a
// geodesic triangle T and its distances to T's three corner samples: exact
// for a vertex (its index record); for a point inside a mesh face, by
// two-side unfolding across the face's edges (§5.1) from the face vertices'
// distances, which are exact when a vertex lies in T and come from case 2.2
// otherwise. Two lifted points are then combined as two vertices are in
// §5.2: one-side unfolding when they share T (case 3.1), otherwise the
// distances from p to q's corners by case 2.2 and a final case 2.2 (3.2).
// This visits the same unfoldings as the paper's cases 4-5 but computes each
// distance once.
//
// The absolute error of that O(1) answer is about the same at every distance,
// so its relative error grows as the points get closer (§6.5): pairs closer
// than kRefineScale geodesic-triangle edges, and pairs in the same or
// adjacent geodesic triangles, are refined by default (DistanceOptions): by
// the length of a path between them (the straightened gradient trace, O(k)
// in the faces it crosses), or by a local exact propagation.
//
// Error bounds. An index built with its accuracy calibration
// (index::AccuracyRecord) gives every answer an absolute error bound: the
// error its kind of answer (O(1), traced, exact) at its distance stayed
// within on all but a small share of held-out exact pairs; 0 for exact
// answers. With the spread bounds (index::SpreadBoundRecord), an O(1)
// answer's bound also grows with its UnfoldingSpread, which flags the pairs
// it errs most on. A caller's tolerance refines every pair whose bound exceeds
// tolerance x distance, by the trace and then exactly.
//
// Thread safety: a QueryEngine is immutable; all const methods are safe from
// any number of threads. Methods that need scratch space take a QueryScratch,
// one per thread.

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/mesh_view.h"
#include "core/query/point_locator.h"
#include "core/query/query_types.h"
#include "core/query/unfold_kernel.h"

namespace geodex::query {

namespace internal {  // core/query/face_lift.h
struct FaceLift;
struct ApproxLift;
struct FaceFrame;
}  // namespace internal

// Per-thread working memory for exact refinement.
class QueryScratch {
 public:
  QueryScratch() = default;

 private:
  friend class QueryEngine;
  std::unique_ptr<geodesic::ExactGeodesicSolver> solver_;
  const mesh::Mesh* mesh_ = nullptr;
};

// QueryEngine answers approximate geodesic queries over one loaded index:
// distances (O(1), refined near pairs as DistanceOptions says, with error
// bounds when the index is calibrated), batches of them, distance fields,
// traced paths and point location (see the header comment for how a
// distance is answered). It is immutable once made: every const method is
// thread-safe and may be called from any number of threads at once; the only
// lazily made state (the mesh for exact refinement) is built once under a
// std::once_flag. Scratch space is explicit (QueryScratch, one per thread).
// It shares ownership of the index, which thus lives as long as the engine.
//
//   GEODEX_ASSIGN_OR_RETURN(std::shared_ptr<const index::Index> index,
//                           index::Index::Open(path));
//   GEODEX_ASSIGN_OR_RETURN(std::shared_ptr<const QueryEngine> engine,
//                           QueryEngine::Create(std::move(index)));
//   absl::StatusOr<double> d = engine->Distance(p, q);  // p, q: SurfacePoints
class QueryEngine {
 public:
  // Makes an engine over `index`, deriving its per-face lifting data
  // (O(faces)). Errors: InvalidArgument for a null index; FailedPrecondition
  // if the index has no geodesic triangles or no samples.
  static absl::StatusOr<std::shared_ptr<const QueryEngine>> Create(
      std::shared_ptr<const index::Index> index, QueryOptions options = {});

  ~QueryEngine();

  const index::Index& index() const { return *index_; }
  const QueryOptions& options() const { return options_; }
  // Every method below takes and returns the index's internal ids, which
  // differ from the mesh file's when the builder repaired or refined it:
  // callers in the file's ids use InputQueries (input_queries.h).

  // Validates a point (mesh::ValidateSurfacePoint with the index's face
  // count and QueryOptions::weight_tolerance): OutOfRange for a face id past
  // the end, InvalidArgument for NaN/Inf/negative weights or weights not
  // summing to 1.
  absl::Status Validate(const SurfacePoint& p) const;

  // Approximate geodesic distance; +inf between components. Validates both
  // points. Symmetric: Distance(p, q) == Distance(q, p) exactly. Pairs are
  // refined as `options` says. With `bound`, *bound is the answer's absolute
  // error bound (see the header comment). `scratch` (optional) keeps the
  // exact solver between calls. Errors: as Validate; FailedPrecondition when
  // a bound or a tolerance is asked of an index without calibration.
  absl::StatusOr<double> Distance(const SurfacePoint& p, const SurfacePoint& q,
                                  const DistanceOptions& options = {},
                                  QueryScratch* scratch = nullptr, double* bound = nullptr) const;

  // Batch: out[i] = Distance(a[i], b[i]), and bounds[i] its bound when
  // `bounds` is not empty (then of out's length). Validates everything first
  // (the error names the pair index). Unrefined pairs allocate nothing.
  absl::Status DistanceBatch(std::span<const SurfacePoint> a, std::span<const SurfacePoint> b,
                             std::span<double> out, const DistanceOptions& options = {},
                             QueryScratch* scratch = nullptr, std::span<double> bounds = {}) const;

  // The length of the straightened gradient trace between the points, as
  // the refinement of Distance computes it (symmetric; a surface path, so
  // never below the geodesic distance); O(k) in the faces it crosses. With
  // `wraps`, whether the trace bends round a mesh vertex. Errors: as
  // Validate; NotFound between components or when no trace reaches the
  // other point.
  absl::StatusOr<double> TracedDistance(const SurfacePoint& p, const SurfacePoint& q,
                                        bool* wraps = nullptr) const;

  // Exact distances from p to every vertex within `radius` of it, by one
  // local exact propagation (not O(1): its cost grows with the faces inside
  // the radius). Entry v is vertex v's distance when it is at most `radius`,
  // a larger value or +inf otherwise. The span lives in `scratch` until its
  // next use. Errors: as Validate; InvalidArgument for a negative radius.
  absl::StatusOr<std::span<const double>> LocalExactDistances(const SurfacePoint& p, double radius,
                                                              QueryScratch& scratch) const;

  // L = sqrt(2 A / (sqrt(3) m)): the edge of an equilateral geodesic
  // triangle when the index's m samples tile the surface's area A.
  double scale_length() const { return scale_length_; }
  // Pairs whose O(1) distance is below this are refined by default (see
  // NearPairs): kRefineScale * scale_length(), plus the calibration's error
  // bound of O(1) answers between 3L and 5L when the index has one.
  double refine_below() const { return refine_below_; }
  // True when the index carries its accuracy calibration (error bounds).
  bool has_error_bounds() const { return index_->accuracy() != nullptr; }

  // The O(1) distance for valid points (no checks; near pairs as in the
  // kUnfold mode): the unfolding of §5, and for near pairs at least the
  // straight-line distance between the points.
  double DistanceUnchecked(const SurfacePoint& p, const SurfacePoint& q) const;

  // True when the points lift into the same or adjacent geodesic triangles.
  bool IsNearPair(const SurfacePoint& p, const SurfacePoint& q) const;

  // The spread of the O(1) answer for valid points: |d_pq - d_qp|, the two
  // orders of case 3.2 (p's distances to q's corners, then q; or q's to p's
  // corners, then p; DistanceUnchecked takes one fixed order). It flags the
  // pairs whose O(1) answer errs most, and scales their error bounds
  // (index::SpreadBoundRecord). 0 for points in one geodesic triangle or in
  // different components.
  double UnfoldingSpread(const SurfacePoint& p, const SurfacePoint& q) const;

  // The paper's linear-interpolation baseline (§6.3), for comparisons.
  double LinearInterpolationDistance(const SurfacePoint& p, const SurfacePoint& q) const;

  // Geodesic path from `from` to `to` by tracing the gradient of the
  // approximate distance field of `from` backwards from `to` (§6.2), then
  // straightened within the faces it crosses (see path_straightening.h). The
  // trace of `to`'s field is tried too, and when the result is still 1%
  // longer than the approximate distance, traces restarted from the vertices
  // around either end; the shortest is returned. O(k) per trace. The
  // first point is `from`, the last `to`, exactly; consecutive points share
  // a mesh face. Errors: as Validate; NotFound between components.
  absl::StatusOr<std::vector<PathPoint>> Path(const SurfacePoint& from,
                                              const SurfacePoint& to) const;
  // Path with QueryOptions::exact_path_corridor = exact_corridor (0: off).
  absl::StatusOr<std::vector<PathPoint>> Path(const SurfacePoint& from, const SurfacePoint& to,
                                              int32_t exact_corridor) const;

  // The gradient trace of Path before straightening, for comparisons. The
  // points must be valid (see Validate).
  absl::StatusOr<std::vector<PathPoint>> TracePath(const SurfacePoint& from,
                                                   const SurfacePoint& to) const;

  // Distance from the nearest of `sources` to every vertex, O(l n): the
  // minimum over sources of DistanceUnchecked (the O(1) mode).
  // Errors: as Validate (naming the source index); InvalidArgument if empty.
  absl::StatusOr<DistanceField> Field(std::span<const SurfacePoint> sources) const;

  // Closest surface point to a 3D position.
  absl::StatusOr<LocatedPoint> Locate(const mesh::Vec3& x) const;

  // Building blocks, exposed for tests and benchmarks.
  LiftedPoint Lift(const SurfacePoint& p) const;
  double LiftedDistance(const LiftedPoint& p, const LiftedPoint& q) const;

 private:
  // The per-face lifting data derived at load (core/query/face_lift.h).
  using FaceLift = internal::FaceLift;
  using ApproxLift = internal::ApproxLift;
  using FaceFrame = internal::FaceFrame;

  QueryEngine(std::shared_ptr<const index::Index> index, QueryOptions options);
  double Matrix(int32_t a, int32_t b) const {
    return static_cast<double>(matrix_[static_cast<size_t>(a) * num_samples_ + b]);
  }
  // Path restart chains for a valid point p: for each vertex one ring out
  // from p's face, that vertex, a vertex of p's face sharing a face with it,
  // then p; consecutive points share a face.
  std::vector<std::vector<PathPoint>> RingChains(const SurfacePoint& p) const;
  // True when the lifts share a geodesic triangle or are in adjacent ones.
  bool AreNear(const LiftedPoint& a, const LiftedPoint& b) const;
  // max(d, |p - q|) for near pairs: the unfolding is weakest there (§6.5)
  // and can come out below the straight line; far pairs practically never
  // do, so they skip the six position loads.
  double AtLeastChord(const SurfacePoint& p, const SurfacePoint& q, double d) const;
  // The 3D position of a surface point.
  mesh::Vec3 PositionOf(const SurfacePoint& p) const;
  // What case 3.2 reads for a pair, p in the triangle of smaller id.
  kernel::FarPair GatherFar(const LiftedPoint& p, const LiftedPoint& q) const;
  // out[k] = LiftedDistance(a[k], b[k]) for kernel::kLanes pairs, the far
  // ones computed together.
  void LiftedDistanceLanes(const LiftedPoint* a, const LiftedPoint* b, double* out) const;
  // Approximate distance from a lifted point to sample `s` (case 2.1/2.2).
  double ToSample(const LiftedPoint& p, int32_t s) const;
  LiftedPoint VertexLift(int32_t v) const {
    const index::VertexRecord& r = records_[v];
    return {r.triangle,
            {r.corner[0], r.corner[1], r.corner[2]},
            {r.distance[0], r.distance[1], r.distance[2]}};
  }
  // The ApproxLift a point of an approximate face uses; `heaviest` is its
  // face vertex of largest weight.
  const ApproxLift& ApproxLiftOf(const FaceLift& fl, int heaviest) const;
  // The ApproxLift of `face` anchored on the triangle of its vertex `k`.
  ApproxLift MakeApproxLift(const int32_t* face_vertices, const FaceFrame& frame, int k) const;
  FaceFrame FaceFrameOf(const int32_t* face_vertices) const;
  // Distances from a face's vertices to the anchor's corners; true when all
  // are exact (the vertices lie in the anchor triangle).
  bool FaceDistances(const int32_t* face_vertices, const LiftedPoint& anchor,
                     double (&d)[3][3]) const;
  // Appends the face's ApproxLifts to approx_lifts_ when it has any.
  FaceLift MakeFaceLift(int32_t face);
  // Bring in what Lift(p) reads: the face and its FaceLift (prefetched),
  // then, once those are in cache, the ApproxLift (loaded: see Touch in the
  // .cc) or the vertex record (prefetched).
  void PrefetchFace(const SurfacePoint& p) const;
  void PrefetchLift(const SurfacePoint& p) const;
  // Lifts a point of a face without a FaceLift; `heaviest` is the face
  // vertex of largest weight (the anchor when the vertices share none).
  LiftedPoint SlowLift(const SurfacePoint& p, int heaviest) const;
  // How an answer was obtained, for its bound.
  enum class AnswerKind { kUnfold, kTrace, kWrappedTrace, kExact };
  // The answer for a pair of canonical points, valid, lifted to lp and lq,
  // whose O(1) distance is `unfolded` = LiftedDistance(lp, lq) (near: the
  // lifts are near), refined as `options` says; its bound in *bound when not
  // null (NaN without calibration).
  double Refine(const SurfacePoint& p, const SurfacePoint& q, const LiftedPoint& lp,
                const LiftedPoint& lq, double unfolded, bool near, const DistanceOptions& options,
                QueryScratch* scratch, double* bound) const;
  // The calibrated bound of an answer of `kind` at distance d (NaN without
  // calibration); `spread` (UnfoldingSpread) scales the bound of an O(1)
  // answer when the index has spread bounds.
  double BoundOf(AnswerKind kind, bool vertex_pair, double d, double spread = 0) const;
  // UnfoldingSpread of lifted points; `unfolded`, when given, is
  // LiftedDistance(p, q), one of the two orders.
  double LiftedSpread(const LiftedPoint& p, const LiftedPoint& q,
                      std::optional<double> unfolded = std::nullopt) const;
  // InvalidArgument for a bad tolerance; FailedPrecondition for a bound or a
  // tolerance without calibration.
  absl::Status CheckOptions(const DistanceOptions& options, bool bounds) const;
  // True when a pair's O(1) answer `unfolded` is not final under `options`.
  bool NeedsRefine(const DistanceOptions& options, bool bounds, bool near, double unfolded) const;
  // The mesh for exact propagations, made on first use.
  const mesh::Mesh* ExactMesh() const;
  // The scratch's exact solver over ExactMesh(), made on first use; null when
  // the mesh cannot be made.
  geodesic::ExactGeodesicSolver* ExactSolver(QueryScratch& scratch) const;
  // The near-pair modes from `from` to `to`; nullopt when they fail.
  std::optional<double> ExactNearDistance(const SurfacePoint& from, const SurfacePoint& to,
                                          QueryScratch* scratch) const;
  // A straightened trace's length; `wraps` when it bends round a mesh vertex
  // (else it is a straight line through the faces it crosses: a local
  // geodesic, practically always the shortest path between near points).
  struct Trace {
    double length;
    bool wraps;
  };
  // A walk's straight path longer than `plausible` is doubted (it may run in
  // a wrong corridor that wraps round nothing) and only kept if nothing
  // shorter is found.
  std::optional<Trace> PathNearDistance(
      const SurfacePoint& from, const SurfacePoint& to,
      double plausible = std::numeric_limits<double>::infinity()) const;
  // The exact shortest path from `from` to `to` among the faces within
  // `steps` edge steps of the faces `path` crosses, or an error (e.g. when
  // that corridor is not a manifold mesh).
  absl::StatusOr<std::vector<PathPoint>> CorridorPath(const std::vector<PathPoint>& path,
                                                      int32_t steps) const;
  // How far ShortestTrace looks beyond the first straightened trace.
  enum class TraceSearch {
    // Path: the trace of the other point's field too, then restarts while
    // the path is still long.
    kFull,
    // Near pairs: the trace of the other point's field only when the first
    // wraps round a vertex; no restarts.
    kNearPair,
  };
  // The straightened trace of `from`'s field back from `to`, or a shorter
  // one found as `search` says.
  absl::StatusOr<std::vector<PathPoint>> ShortestTrace(const SurfacePoint& from,
                                                       const SurfacePoint& to,
                                                       TraceSearch search) const;
  SurfacePoint Canonical(const SurfacePoint& p) const;
  // A canonical vertex point re-expressed in the vertex's face of lowest id,
  // other points unchanged. Only the traces need it (they start from the
  // point's face; the O(1) lift of a vertex is its record, whatever the
  // face), so it stays off the batch path.
  SurfacePoint InLowestFaceIfVertex(const SurfacePoint& c) const;

  std::shared_ptr<const index::Index> index_;
  QueryOptions options_;
  MeshView view_;  // the index's positions, faces and twins
  std::span<const float> matrix_;
  std::span<const index::VertexRecord> records_;
  std::span<const index::GeodesicTriangle> triangles_;
  int32_t num_samples_ = 0;
  PointLocator locator_;
  std::vector<kernel::Frame<double>> frames_;  // 3 per geodesic triangle, derived at load
  std::vector<FaceLift> face_lifts_;           // one per face, derived at load
  std::vector<ApproxLift> approx_lifts_;       // of the approximate faces
  double scale_length_ = 0;
  // Pairs whose O(1) answer is below this are refined by default:
  // kRefineScale * scale_length_, plus the calibration's bound at 3L-5L.
  double refine_below_ = 0;
  // The mesh for exact refinement, made on first use (ExactMesh).
  mutable std::once_flag mesh_once_;
  mutable std::unique_ptr<mesh::Mesh> mesh_;
};

}  // namespace geodex::query
