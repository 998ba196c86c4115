#pragma once

// The queries of a loaded index in its internal ids (Xin, Ying & He 2012):
// the part behind the public facade (input_queries.h), which reads and
// validates points, translates ids and calls this. The builder's validation
// (core/validation) uses it directly, since it works in internal ids. Each
// idea has its own part, in a folder named after the paper's step. Parts
// take parts (or plain functions), never the engine; the engine composes
// them:
//
//   o1/lifting.h               §5.1  a surface point -> its geodesic triangle
//                                    and distances to the triangle's corners
//   o1/lifted_unfolding.h      §5.2  two lifted points -> their O(1) distance
//   o1/unfold_kernel.h         §5.2  the same, four far pairs at a time
//   paths/gradient_path.h      §6.2  paths by tracing the approximate field's
//                                    gradient; paths/path_straightening.h
//                                    straightens them
//   paths/chord_walk.h         §6.5  a near pair's path length, by the chord's
//                                    corridor (paths/strip_funnel.h unfolds it)
//   bounds/refinement.h        §6.5  which answers are refined, and how
//   bounds/error_bounds.h      §6.5  the calibrated bound of each kind of answer
//   exact/local_exact.h              exact propagations near a point
//   fields/distance_field.h    §6.2  fields from several sources
//   locate/point_locator.h           the closest surface point to a position
//
// Queries made of the engine's own answers (the exponential map of §6.4 is
// one) are parts over SurfaceDistances (surface_distances.h), which
// WithDistances hands them; the facade calls them, and the engine has no
// method of theirs (core/query/README.md, "Adding a query").
//
// Points are valid (mesh::ValidateSurfacePoint against the index's faces)
// and in internal ids: the facade checks them once, when they enter.
//
// Thread safety: a QueryEngine is immutable; every const method is safe from
// any number of threads. The only lazily made state (the mesh for exact
// refinement) is built once under a std::once_flag. Scratch space is
// explicit (QueryScratch, one per thread). The engine shares ownership of the
// index, which thus lives as long as it does.

#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/internal/bounds/error_bounds.h"
#include "core/query/engine/internal/paths/gradient_path.h"
#include "core/query/engine/internal/o1/lifted_unfolding.h"
#include "core/query/engine/internal/o1/lifting.h"
#include "core/query/engine/internal/exact/local_exact.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/internal/locate/point_locator.h"
#include "core/query/engine/query_knobs.h"
#include "core/query/engine/internal/bounds/refinement.h"
#include "core/query/engine/surface_distances.h"
#include "core/query/engine/query_scratch.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

class QueryEngine {
 public:
  // Makes an engine over `index`, deriving its per-face lifting data
  // (O(faces)). Errors: InvalidArgument for a null index; FailedPrecondition
  // if the index has no geodesic triangles or no samples.
  static absl::StatusOr<std::shared_ptr<const QueryEngine>> Create(
      std::shared_ptr<const index::Index> index, QueryOptions options = {});

  QueryEngine(const QueryEngine&) = delete;
  QueryEngine& operator=(const QueryEngine&) = delete;

  const index::Index& index() const { return *index_; }
  const QueryOptions& options() const { return options_; }

  // Approximate geodesic distance; +inf between components. Symmetric:
  // Distance(p, q) == Distance(q, p) exactly. Pairs are refined as `options`
  // says (refinement.h). With `bound`, *bound is the answer's absolute error
  // bound (error_bounds.h). `scratch` (optional) keeps the exact solver
  // between calls. Errors: FailedPrecondition when a bound or a tolerance is
  // asked of an index without calibration; InvalidArgument for a bad
  // tolerance.
  absl::StatusOr<double> Distance(const SurfacePoint& p, const SurfacePoint& q,
                                  const DistanceOptions& options = {},
                                  QueryScratch* scratch = nullptr, double* bound = nullptr) const;

  // Batch: out[i] = Distance(a[i], b[i]), and bounds[i] its bound when
  // `bounds` is not empty (then of out's length). Unrefined pairs allocate
  // nothing. Errors: as Distance; InvalidArgument when the lengths differ.
  absl::Status DistanceBatch(std::span<const SurfacePoint> a, std::span<const SurfacePoint> b,
                             std::span<double> out, const DistanceOptions& options = {},
                             QueryScratch* scratch = nullptr, std::span<double> bounds = {}) const;

  // The length of a near pair's surface path (chord_walk.h's
  // NearPathLength: the chord's walks, else the gradient trace; symmetric,
  // never below the geodesic distance); with `wraps`, whether it bends round
  // a mesh vertex. Errors: NotFound between components or when no path
  // reaches the other point.
  absl::StatusOr<double> TracedDistance(const SurfacePoint& p, const SurfacePoint& q,
                                        bool* wraps = nullptr) const;

  // The surface path the default refinement answers a near pair with, as
  // TracedDistance: the walks' local geodesic (the trace when the walks are
  // off); NotFound when the walks vouch for none, for the default mode then
  // answers exactly. What the trace bounds are calibrated on.
  absl::StatusOr<double> WalkedDistance(const SurfacePoint& p, const SurfacePoint& q,
                                        bool* wraps = nullptr) const;

  // Exact distances from p to every vertex within `radius` (local_exact.h;
  // not O(1)). Entry v is vertex v's distance when it is at most `radius`, a
  // larger value or +inf otherwise; the span lives in `scratch` until its
  // next use. Errors: InvalidArgument for a negative radius.
  absl::StatusOr<std::span<const double>> LocalExactDistances(const SurfacePoint& p, double radius,
                                                              QueryScratch& scratch) const;

  // L = sqrt(2 A / (sqrt(3) m)): the edge of an equilateral geodesic
  // triangle when the index's m samples tile the surface's area A.
  double scale_length() const { return scale_length_; }
  // Pairs whose O(1) distance is below this are refined by default:
  // kRefineScale * scale_length(), plus the calibration's bound of O(1)
  // answers between 3L and 5L (a pair answered beyond 3L may be closer).
  double refine_below() const { return refine_below_; }
  // L1000 = sqrt(2 A / (sqrt(3) 1000)): the unit of
  // DistanceOptions::refine_below_l1000, fixed by the surface whatever m.
  double l1000() const { return l1000_; }
  // True when the index carries its accuracy calibration (error bounds).
  bool has_error_bounds() const { return bounds_.available(); }

  // Geodesic path from `from` to `to` (gradient_path.h): the shortest of the
  // straightened traces; with an exact corridor of K > 0 edge steps (default
  // QueryOptions::exact_path_corridor), the exact path within it when
  // shorter (not O(k)). The first point is `from`, the last `to`, exactly;
  // consecutive points share a mesh face. Errors: NotFound between
  // components.
  absl::StatusOr<std::vector<PathPoint>> Path(const SurfacePoint& from,
                                              const SurfacePoint& to) const;
  absl::StatusOr<std::vector<PathPoint>> Path(const SurfacePoint& from, const SurfacePoint& to,
                                              int32_t exact_corridor) const;

  // Distance from the nearest of `sources` to every vertex, O(l n)
  // (distance_field.h). Errors: InvalidArgument if empty.
  absl::StatusOr<DistanceField> Field(std::span<const SurfacePoint> sources) const;

  // The exact distance from the nearest of `sources` to every vertex within
  // options.radius, by one exact propagation from all of them
  // (LocalExact::DistancesWithin): its cost follows the vertices reached,
  // not the mesh, and is not O(1) per vertex. `scratch` keeps the solver
  // between calls. Errors: InvalidArgument if empty or for a radius that is
  // not finite and > 0; ResourceExhausted past options.max_vertices.
  absl::StatusOr<RadiusField> FieldWithin(std::span<const SurfacePoint> sources,
                                          const FieldWithinOptions& options,
                                          QueryScratch& scratch) const;

  // Calls `query` with this engine's SurfaceDistances: Distance refined as
  // `options` says and FieldWithin, both keeping `scratch` (a local one when
  // null) between calls. Returns what `query` returns. How a query made of
  // the engine's answers is run (surface_distances.h).
  template <typename Query>
  auto WithDistances(const DistanceOptions& options, QueryScratch* scratch, Query&& query) const {
    QueryScratch local;
    QueryScratch& s = scratch != nullptr ? *scratch : local;
    auto distance = [&](const SurfacePoint& from, const SurfacePoint& p) {
      return Distance(from, p, options, &s);
    };
    auto exact_within = [&](const SurfacePoint& from, double radius) {
      FieldWithinOptions within;
      within.radius = radius;
      return FieldWithin(std::span<const SurfacePoint>(&from, 1), within, s);
    };
    return std::forward<Query>(query)(SurfaceDistances{view_, scale_length_, distance, exact_within});
  }

  // Closest surface point to a 3D position.
  absl::StatusOr<LocatedPoint> Locate(const mesh::Vec3& x) const;

  // Building blocks of the builder's calibration, tests, benchmarks and
  // comparisons.
  //
  // The O(1) answer, never refined (lifting.h O1Distance).
  double O1Distance(const SurfacePoint& p, const SurfacePoint& q) const;
  // True when the points lift into the same or adjacent geodesic triangles.
  bool IsNearPair(const SurfacePoint& p, const SurfacePoint& q) const;
  // LiftedUnfolding::Spread of the points' lifts.
  double UnfoldingSpread(const SurfacePoint& p, const SurfacePoint& q) const;
  // The paper's linear-interpolation baseline (§6.3).
  double LinearInterpolationDistance(const SurfacePoint& p, const SurfacePoint& q) const;
  // The gradient trace of Path before straightening.
  absl::StatusOr<std::vector<PathPoint>> TracePath(const SurfacePoint& from,
                                                   const SurfacePoint& to) const;
  LiftedPoint Lift(const SurfacePoint& p) const { return lifting_.Lift(p); }

 private:
  friend absl::StatusOr<std::shared_ptr<const QueryEngine>> CreateQueryEngine(
      std::shared_ptr<const index::Index>, QueryOptions, QueryKnobs);
  QueryEngine(std::shared_ptr<const index::Index> index, QueryOptions options, QueryKnobs knobs);

  std::shared_ptr<const index::Index> index_;
  QueryOptions options_;
  QueryKnobs knobs_;
  MeshView view_;  // the index's positions, faces and twins
  // The parts, in the order they are made (each uses those above it).
  LiftedUnfolding unfolding_;
  Lifting lifting_;
  ErrorBounds bounds_;
  LocalExact exact_;
  GradientPaths paths_;
  PointLocator locator_;
  double scale_length_;
  double refine_below_;
  double l1000_;
  Refiner refiner_;
};

}  // namespace geodex::query
