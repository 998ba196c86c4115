#pragma once

// Refinement of the O(1) answer (Xin, Ying & He 2012, §6.5). Its absolute
// error is about the same at every distance, so its relative error grows as
// the points get closer: pairs that may be closer than kRefineScale
// geodesic-triangle edges, and pairs in the same or adjacent geodesic
// triangles, are answered by default by a local geodesic the chord's walks
// find (chord_walk.h), else exactly by a propagation confined to a region
// round the pair (local_exact.h, core/geodesic/confined_geodesic.h); or all
// exactly, as DistanceOptions::near_pairs says. A caller's tolerance
// answers exactly every pair whose error bound (error_bounds.h) exceeds
// tolerance x distance.
//
// Thread safety: immutable; every method is const and thread-safe, with one
// QueryScratch per thread.

#include <algorithm>

#include "core/query/engine/internal/bounds/error_bounds.h"
#include "core/query/engine/internal/exact/local_exact.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/internal/o1/lifted_unfolding.h"
#include "core/query/engine/internal/paths/gradient_path.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

// A near pair's walk no longer than (1 + kCertifiedExcess) x the chord is
// taken as it is; a longer one is checked exactly (Refiner::Refine). Below
// the 2% every near answer must keep, above most walks on smooth parts of a
// surface (tests/bench/accuracy.md, "Walks the chord certifies").
inline constexpr double kCertifiedExcess = 0.02;

// The cut bound (cut_bound.h) that certifies a near pair's walk the chord
// does not: its region reaches kCutReach x the walk's length round the
// points, so that an edge on the region's rim, lower than `reach` by at most
// the span of a face, seldom undercuts the walk's certificate; a region of
// more than kCutFaces faces (a long or a wide pair) leaves the walk to the
// exact check, whose own region is then of the same order.
inline constexpr double kCutReach = 1.1;
inline constexpr int kCutFaces = 4096;

// A shot (chord_walk.h) of a pair refined only by a raised threshold, longer
// than the O(1) answer by more than this share, is doubted, however wide the
// answer's bound: where the secant wanders, a
// shot may settle round the wrong side of a feature, and the bound, wide
// where the O(1) answer is unsure, let such paths 12-26% too long through
// on four of twelve shared meshes. Held at 3%, no bin's p99 or largest error
// is worse than the walks' and traces' alone (1.5% and 5% measured the
// same on four meshes; tests/bench/accuracy.md, "The every-distance mode").
// A correct shot beyond it is traced instead.
inline constexpr double kShotExcess = 0.03;

// A pair whose O(1) answer lands above refine_below is still refined when
// its chord is below and the answer below kChordNet x refine_below: the
// calibrated margin in refine_below covers 99.5% of the O(1) answer's
// overestimates, this its tail (tests/bench/accuracy.md, "Pairs the O(1)
// answer pushes past the threshold"), at the price of walking the pairs just
// past refine_below on curved parts, where the chord is shorter than the
// geodesic.
inline constexpr double kChordNet = 1.5;

class Refiner {
 public:
  // Over the engine's parts, which must outlive this object. Pairs whose
  // O(1) answer is below `refine_below` are refined by default, or below
  // DistanceOptions::refine_below_l1000 x `l1000` where that is more.
  // `walk`: near-pair paths try the chord's corridors first (chord_walk.h).
  Refiner(const MeshView& view, const LiftedUnfolding& unfolding, const ErrorBounds& bounds,
          const GradientPaths& paths, const LocalExact& exact, bool walk, double refine_below,
          double l1000)
      : view_(view),
        unfolding_(unfolding),
        bounds_(bounds),
        paths_(paths),
        exact_(exact),
        walk_(walk),
        refine_below_(refine_below),
        l1000_(l1000) {}

  // True when the O(1) answer `unfolded` of the pair p, q (any valid points)
  // is not final under `options` (`bounds`: a bound is asked for; `near`:
  // the lifts are near).
  bool Needs(const DistanceOptions& options, bool bounds, bool near, double unfolded,
             const SurfacePoint& p, const SurfacePoint& q) const;

  // The answer for a pair of canonical points, valid, lifted to lp and lq,
  // whose O(1) distance is `unfolded` (near: the lifts are near), refined as
  // `options` says; its bound in *bound when not null (NaN without
  // calibration). Symmetric in the points.
  double Refine(const SurfacePoint& p, const SurfacePoint& q, const LiftedPoint& lp,
                const LiftedPoint& lq, double unfolded, bool near, const DistanceOptions& options,
                QueryScratch* scratch, double* bound) const;

 private:
  class Pair;  // one pair's refinement (refinement.cc)

  MeshView view_;
  const LiftedUnfolding& unfolding_;
  const ErrorBounds& bounds_;
  const GradientPaths& paths_;
  const LocalExact& exact_;
  // True when the pair may be closer than `below`: its O(1) answer is
  // below it, or overestimates by less than kChordNet and the chord, never
  // longer than the geodesic, is below it.
  bool MayBeNear(double unfolded, double below, const SurfacePoint& p, const SurfacePoint& q) const;
  // The threshold of a call: refine_below, raised by the options.
  double RefineBelow(const DistanceOptions& options) const {
    return std::max(refine_below_, options.refine_below_l1000 * l1000_);
  }

  bool walk_;
  double refine_below_;
  double l1000_;
};

}  // namespace geodex::query
