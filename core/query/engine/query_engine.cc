#include "core/query/engine/query_engine.h"

#include <cmath>
#include <tuple>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/geometry/sample_spacing.h"
#include "core/query/engine/internal/fields/distance_field.h"
#include "core/query/engine/internal/paths/chord_walk.h"
#include "core/query/engine/internal/paths/path_straightening.h"

namespace geodex::query {
namespace {

// L of the mesh `view` tiled by m samples.
double ScaleLength(const MeshView& view, int32_t num_samples) {
  return geometry::SampleSpacing(view.Area(), num_samples);
}

}  // namespace

absl::StatusOr<std::shared_ptr<const QueryEngine>> QueryEngine::Create(
    std::shared_ptr<const index::Index> index, QueryOptions options) {
  return CreateQueryEngine(std::move(index), options, {});
}

absl::StatusOr<std::shared_ptr<const QueryEngine>> CreateQueryEngine(
    std::shared_ptr<const index::Index> index, QueryOptions options, QueryKnobs knobs) {
  if (index == nullptr) return absl::InvalidArgumentError("no index");
  if (index->num_triangles() == 0 || index->num_samples() == 0) {
    return absl::FailedPreconditionError("the index has no geodesic triangles");
  }
  return std::shared_ptr<const QueryEngine>(new QueryEngine(std::move(index), options, knobs));
}

QueryEngine::QueryEngine(std::shared_ptr<const index::Index> index, QueryOptions options,
                         QueryKnobs knobs)
    : index_(std::move(index)),
      options_(options),
      knobs_(knobs),
      view_{index_->positions(), index_->faces(), index_->twins()},
      unfolding_(*index_, knobs_.vector_lanes),
      lifting_(view_, index_->vertices(), unfolding_),
      bounds_(*index_),
      exact_(*index_, view_),
      paths_(view_, lifting_, unfolding_, knobs_.straighten_paths),
      locator_(index_->positions(), index_->faces(), index_->bvh_nodes(), index_->bvh_faces()),
      scale_length_(ScaleLength(view_, index_->num_samples())),
      // A pair whose O(1) answer overestimates lands above 3L while the pair
      // is closer: with a calibration, refine every pair that may be closer
      // than 3L (its answer minus the bound of answers between 3L and 5L).
      refine_below_(kRefineScale * scale_length_ + bounds_.RefineMargin()),
      l1000_(ScaleLength(view_, 1000)),
      refiner_(view_, unfolding_, bounds_, paths_, exact_, knobs_.walk_near_pairs, refine_below_,
               l1000_) {}

absl::StatusOr<double> QueryEngine::Distance(const SurfacePoint& p, const SurfacePoint& q,
                                             const DistanceOptions& options, QueryScratch* scratch,
                                             double* bound) const {
  GEODEX_RETURN_IF_ERROR(bounds_.CheckOptions(options, bound != nullptr));
  const SurfacePoint a = view_.Canonical(p), b = view_.Canonical(q);
  const LiftedPoint la = lifting_.Lift(a), lb = lifting_.Lift(b);
  const double d = unfolding_.Distance(la, lb);
  const bool near = unfolding_.AreNear(la, lb);
  if (!refiner_.Needs(options, bound != nullptr, near, d, a, b)) return d;
  return refiner_.Refine(a, b, la, lb, d, near, options, scratch, bound);
}

absl::Status QueryEngine::DistanceBatch(std::span<const SurfacePoint> a,
                                        std::span<const SurfacePoint> b, std::span<double> out,
                                        const DistanceOptions& options, QueryScratch* scratch,
                                        std::span<double> bounds) const {
  if (a.size() != b.size() || a.size() != out.size() ||
      (!bounds.empty() && bounds.size() != out.size())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("batch arrays differ in length (%d, %d, %d, bounds %d)", a.size(), b.size(),
                        out.size(), bounds.size()));
  }
  const bool want_bounds = !bounds.empty();
  GEODEX_RETURN_IF_ERROR(bounds_.CheckOptions(options, want_bounds));
  // One solver for the batch's exact refinements when the caller keeps none.
  QueryScratch own;
  if (scratch == nullptr) scratch = &own;
  auto refine = [&](size_t k, const LiftedPoint& p, const LiftedPoint& q) {
    const bool near = unfolding_.AreNear(p, q);
    if (refiner_.Needs(options, want_bounds, near, out[k], a[k], b[k])) {
      out[k] = refiner_.Refine(view_.Canonical(a[k]), view_.Canonical(b[k]), p, q, out[k], near,
                               options, scratch, want_bounds ? &bounds[k] : nullptr);
    }
  };
  const size_t n = a.size();
  // A query's loads depend on each other (face -> face lift -> approximate
  // lift or vertex record -> geodesic triangles -> sample matrix), so the
  // batch runs as a software pipeline: the faces 16 pairs ahead are
  // prefetched, what their lifts read next is brought in 12 ahead (see
  // Lifting::PrefetchLift), the points 8 ahead are
  // lifted (and the frames and matrix entries their distance will read are
  // prefetched), and the distances are computed from the lifts, kLanes pairs
  // per instruction.
  constexpr size_t kFaceAhead = 16, kLiftDataAhead = 12, kLiftAhead = 8, kRing = 16;
  constexpr size_t W = kernel::kLanes;
  static_assert(kLiftAhead % W == 0 && kRing % W == 0 && kRing >= kLiftAhead + W);
  LiftedPoint lift_a[kRing], lift_b[kRing];
  auto lift = [&](size_t j) {
    LiftedPoint& p = lift_a[j % kRing];
    LiftedPoint& q = lift_b[j % kRing];
    p = lifting_.Lift(view_.Canonical(a[j]));
    q = lifting_.Lift(view_.Canonical(b[j]));
    unfolding_.Prefetch(p, q);
  };
  for (size_t j = 0; j < std::min(n, kLiftAhead); ++j) lift(j);
  size_t i = 0;
  for (; i + W <= n; i += W) {
    for (size_t k = i; k < i + W; ++k) {
      if (k + kFaceAhead < n) {
        lifting_.PrefetchFace(a[k + kFaceAhead]);
        lifting_.PrefetchFace(b[k + kFaceAhead]);
      }
      if (k + kLiftDataAhead < n) {
        lifting_.PrefetchLift(a[k + kLiftDataAhead]);
        lifting_.PrefetchLift(b[k + kLiftDataAhead]);
      }
    }
    unfolding_.DistanceLanes(&lift_a[i % kRing], &lift_b[i % kRing], &out[i]);
    for (size_t k = i; k < i + W; ++k) {
      refine(k, lift_a[k % kRing], lift_b[k % kRing]);
      if (k + kLiftAhead < n) lift(k + kLiftAhead);
    }
  }
  for (; i < n; ++i) {
    const LiftedPoint& p = lift_a[i % kRing];
    const LiftedPoint& q = lift_b[i % kRing];
    out[i] = unfolding_.Distance(p, q);
    refine(i, p, q);
  }
  return absl::OkStatus();
}

absl::StatusOr<double> QueryEngine::TracedDistance(const SurfacePoint& p, const SurfacePoint& q,
                                                   bool* wraps) const {
  const SurfacePoint a = view_.InLowestFaceIfVertex(view_.Canonical(p)),
                     b = view_.InLowestFaceIfVertex(view_.Canonical(q));
  const bool swap = std::tie(b.face, b.w) < std::tie(a.face, a.w);
  const std::optional<NearPath> t =
      NearPathLength(view_, paths_, swap ? b : a, swap ? a : b, knobs_.walk_near_pairs);
  if (!t) return absl::NotFoundError("no trace between the points");
  if (wraps != nullptr) *wraps = t->wraps;
  return t->length;
}

absl::StatusOr<double> QueryEngine::WalkedDistance(const SurfacePoint& p, const SurfacePoint& q,
                                                   bool* wraps) const {
  if (!knobs_.walk_near_pairs) return TracedDistance(p, q, wraps);
  const SurfacePoint a = view_.InLowestFaceIfVertex(view_.Canonical(p)),
                     b = view_.InLowestFaceIfVertex(view_.Canonical(q));
  const bool swap = std::tie(b.face, b.w) < std::tie(a.face, a.w);
  const NearWalk walk = WalkNearPair(view_, swap ? b : a, swap ? a : b);
  if (!walk.path)
    return absl::NotFoundError("the walks found no local geodesic between the points");
  if (wraps != nullptr) *wraps = walk.path->wraps;
  return walk.path->length;
}

absl::StatusOr<std::span<const double>> QueryEngine::LocalExactDistances(
    const SurfacePoint& p, double radius, QueryScratch& scratch) const {
  return exact_.Distances(view_.Canonical(p), radius, scratch);
}

absl::StatusOr<std::vector<PathPoint>> QueryEngine::Path(const SurfacePoint& from,
                                                         const SurfacePoint& to) const {
  return Path(from, to, options_.exact_path_corridor);
}

absl::StatusOr<std::vector<PathPoint>> QueryEngine::Path(const SurfacePoint& from,
                                                         const SurfacePoint& to,
                                                         int32_t exact_corridor) const {
  GEODEX_ASSIGN_OR_RETURN(std::vector<PathPoint> path,
                          paths_.Shortest(from, to, GradientPaths::Search::kFull));
  if (exact_corridor <= 0) return path;
  absl::StatusOr<std::vector<PathPoint>> exact = exact_.CorridorPath(path, exact_corridor);
  if (exact.ok() && PathLength(*exact) < PathLength(path)) {
    exact->front() = path.front();
    exact->back() = path.back();
    return *std::move(exact);
  }
  return path;
}

absl::StatusOr<std::vector<PathPoint>> QueryEngine::TracePath(const SurfacePoint& from,
                                                              const SurfacePoint& to) const {
  return paths_.Trace(from, to);
}

absl::StatusOr<DistanceField> QueryEngine::Field(std::span<const SurfacePoint> sources) const {
  if (sources.empty()) return absl::InvalidArgumentError("no sources given");
  std::vector<SurfacePoint> canonical;
  canonical.reserve(sources.size());
  for (const SurfacePoint& source : sources) canonical.push_back(view_.Canonical(source));
  return ApproximateField(view_, lifting_, unfolding_, canonical);
}

absl::StatusOr<RadiusField> QueryEngine::FieldWithin(std::span<const SurfacePoint> sources,
                                                     const FieldWithinOptions& options,
                                                     QueryScratch& scratch) const {
  if (sources.empty()) return absl::InvalidArgumentError("no sources given");
  std::vector<SurfacePoint> canonical;
  canonical.reserve(sources.size());
  for (const SurfacePoint& source : sources) canonical.push_back(view_.Canonical(source));
  return exact_.DistancesWithin(canonical, options.radius, options.max_vertices, scratch);
}

absl::StatusOr<LocatedPoint> QueryEngine::Locate(const mesh::Vec3& x) const {
  return locator_.Locate(x);
}

double QueryEngine::O1Distance(const SurfacePoint& p, const SurfacePoint& q) const {
  return query::O1Distance(view_, lifting_, unfolding_, p, q);
}

bool QueryEngine::IsNearPair(const SurfacePoint& p, const SurfacePoint& q) const {
  return unfolding_.AreNear(lifting_.Lift(view_.Canonical(p)), lifting_.Lift(view_.Canonical(q)));
}

double QueryEngine::UnfoldingSpread(const SurfacePoint& p, const SurfacePoint& q) const {
  return unfolding_.Spread(lifting_.Lift(view_.Canonical(p)), lifting_.Lift(view_.Canonical(q)));
}

double QueryEngine::LinearInterpolationDistance(const SurfacePoint& p,
                                                const SurfacePoint& q) const {
  return unfolding_.LinearInterpolation(lifting_.Lift(view_.Canonical(p)),
                                        lifting_.Lift(view_.Canonical(q)));
}

}  // namespace geodex::query
