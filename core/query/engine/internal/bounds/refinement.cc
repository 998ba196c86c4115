#include "core/query/engine/internal/bounds/refinement.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <tuple>

#include "core/query/engine/internal/paths/chord_walk.h"
#include "core/query/engine/internal/paths/cut_bound.h"

namespace geodex::query {
bool Refiner::MayBeNear(double unfolded, double below, const SurfacePoint& p,
                        const SurfacePoint& q) const {
  return unfolded < below || (unfolded < kChordNet * below &&
                              (view_.PositionOf(p) - view_.PositionOf(q)).norm() < below);
}

bool Refiner::Needs(const DistanceOptions& options, bool bounds, bool near, double unfolded,
                    const SurfacePoint& p, const SurfacePoint& q) const {
  return near || bounds || options.tolerance > 0 ||
         (options.near_pairs != NearPairs::kUnfold &&
          MayBeNear(unfolded, RefineBelow(options), p, q));
}

double Refiner::Refine(const SurfacePoint& p_in, const SurfacePoint& q_in, const LiftedPoint& lp,
                       const LiftedPoint& lq, double unfolded, bool near,
                       const DistanceOptions& options, QueryScratch* scratch, double* bound) const {
  const SurfacePoint p = view_.InLowestFaceIfVertex(p_in), q = view_.InLowestFaceIfVertex(q_in);
  if (!(unfolded < kInf)) {  // different components: exactly unreachable
    if (bound != nullptr) *bound = bounds_.Of(AnswerKind::kExact, false, unfolded);
    return unfolded;
  }
  // The refinements work from one point to the other: from the smaller, so
  // that the answer is symmetric.
  const bool swap = std::tie(q.face, q.w) < std::tie(p.face, p.w);
  const SurfacePoint& from = swap ? q : p;
  const SurfacePoint& to = swap ? p : q;
  auto at_vertex = [](const SurfacePoint& x) { return x.w[0] == 1 || x.w[1] == 1 || x.w[2] == 1; };
  const bool vertex_pair = at_vertex(p) && at_vertex(q);
  const double chord = (view_.PositionOf(p) - view_.PositionOf(q)).norm();
  double d = near ? std::max(unfolded, chord) : unfolded;
  AnswerKind kind = AnswerKind::kUnfold;
  // The bound of an answer; the spread of an O(1) answer is computed once,
  // when first needed.
  std::optional<double> spread;
  auto bound_of = [&](AnswerKind k, double at) {
    if (k == AnswerKind::kUnfold && !spread) {
      spread = bounds_.has_spread() ? unfolding_.Spread(lp, lq, unfolded) : 0;
    }
    return bounds_.Of(k, vertex_pair, at, spread.value_or(0));
  };
  // Exact answers run a propagation confined to a region round the pair
  // (its cost follows the region), else one over the whole mesh from `from`
  // that stops at `to`.
  QueryScratch own;
  QueryScratch& solvers = scratch != nullptr ? *scratch : own;
  // `path_length`: the length of a surface path between the points, if known.
  NearPairStats& stats = solvers.near_pair_stats();
  // `seeds`: the faces the region starts from (none: a chain of faces from
  // one point to the other).
  auto exact = [&](double path_length = kInf, std::span<const int32_t> seeds = {}) {
    std::optional<double> e = exact_.ConfinedDistance(from, to, seeds, solvers, path_length);
    if (!e) e = exact_.NearDistance(from, to, &solvers);
    if (!e) return false;
    d = *e;
    kind = AnswerKind::kExact;
    return true;
  };
  // The O(1) answer plus its bound: a straight walk longer than that is
  // doubted (NaN without calibration: none is).
  auto plausible = [&] {
    const double limit = unfolded + bound_of(AnswerKind::kUnfold, unfolded);
    return std::isnan(limit) ? kInf : limit;
  };
  auto take = [&](const NearPath& path) {
    d = path.length;
    kind = path.wraps ? AnswerKind::kWrappedTrace : AnswerKind::kTrace;
    return true;
  };
  // Every surface path, the geodesic too, is at least as long as a lower
  // bound: first the chord |pq|, then, for a path the chord leaves
  // uncertified, the two chords through the border of the faces nearer p
  // (cut_bound.h), which follow a curved surface closer. A path within
  // kCertifiedExcess of the bound errs less than that, whichever corridor
  // it took. A longer walk may be a local geodesic round the wrong side of a
  // sharp edge or a bump, which no calibrated bound sees (the shortest path
  // crosses the feature elsewhere; tests/bench/accuracy.md, "Walks the chord
  // certifies"): it is checked by an exact propagation, which its length
  // prunes from the start. `floor`: the best lower bound known.
  double floor = chord;
  bool cut_tried = false;
  auto certified = [&](double length) {
    if (length <= (1 + kCertifiedExcess) * floor) return true;
    if (cut_tried) return false;
    cut_tried = true;
    floor = std::max(floor, CutLowerBound(view_, from, to, kCutReach * length, kCutFaces,
                                          &solvers.walks()));
    return length <= (1 + kCertifiedExcess) * floor;
  };
  // A pair refined only because the request raised the threshold past the
  // index's own (DistanceOptions::refine_below_l1000) is beyond the band
  // where the chord certifies walks: on a curved surface most of its walks
  // are more than 2% longer than the chord. There a walk the corridor
  // vouches for, no longer than the O(1) answer plus its bound, is taken as
  // it is (a wrong corridor's walk is mostly longer than that), and a pair
  // whose walks all fail keeps its O(1) answer: the mode's promise is p99
  // in every band, not the near pairs' largest error
  // (tests/bench/accuracy.md, "The every-distance mode").
  const bool raised_only = !near && !MayBeNear(unfolded, refine_below_, p, q);
  // A near pair: the chord's walks find a local geodesic for most; the rest
  // (both walks failed, bent at several saddles, or ran longer than is
  // plausible) are answered exactly, which the gradient trace that used to
  // answer them erred up to 5% at p99 on, in about the same time
  // (tests/bench/exact_geodesics.md). The trace stays for an index whose mesh cannot
  // be rebuilt for exact propagation, and for `walk_` off (benchmarks).
  auto near_path = [&] {
    ++stats.pairs;
    if (walk_) {
      // Beyond the index's own threshold geodesics are shot first, aimed as
      // the O(1) field of `to` sees the geodesic leave `from` and held within
      // kShotExcess of the O(1) answer: there the chord's walks mostly fail
      // (the chord leaves the surface) and a trace costs ten shots. Near
      // pairs keep the chord's walks, which settle most of them.
      const NearWalk walk =
          raised_only ? WalkNearPair(view_, from, to,
                                     {.plausible = plausible(),
                                      .plausible_shot = (1 + kShotExcess) * unfolded,
                                      .heading = paths_.Heading(from, to),
                                      .shoot = true},
                                     &solvers)
                      : WalkNearPair(view_, from, to, {.plausible = plausible()}, &solvers);
      if (walk.path && (raised_only || certified(walk.path->length))) return take(*walk.path);
      // A doubted walk (bent at several saddles, or longer than is
      // plausible) is a surface path all the same: within the bound's
      // certificate it is taken.
      if (!raised_only && !walk.path && walk.doubted && certified(*walk.doubted)) {
        return take(NearPath{*walk.doubted, true});
      }
      if (raised_only) {
        // The gradient trace finds the corridor where the chord's does not
        // (the chord leaves the surface over a curved band); a trace
        // longer than is plausible keeps the O(1) answer.
        ++stats.traces;
        const std::optional<NearPath> t =
            NearPathLength(view_, paths_, from, to, false, plausible());
        if (t && t->length <= plausible()) return take(*t);
        ++stats.raised_kept;
        return false;
      }
      // The doubted walk's length prunes the propagation from its first
      // window, and its corridor, where the shortest path mostly runs, is
      // the first region (a chain of faces found by a search round the
      // pair cost more than the propagation in it).
      const double upper = walk.path ? walk.path->length : walk.doubted.value_or(kInf);
      const bool solved = exact(upper, walk.corridor);
      ++stats.exact_solves;
      stats.exact_with_walk += walk.path || walk.doubted;
      if (const auto* confined = solvers.solvers().last_confined) {
        stats.exact_rounds += confined->stats().rounds;
        stats.exact_region_faces += confined->stats().region_faces;
        stats.exact_windows += confined->stats().windows_created;
      }
      if (solved) return true;
      if (walk.path) return take(*walk.path);  // a mesh without exact propagation
    }
    ++stats.traces;
    const std::optional<NearPath> t = NearPathLength(view_, paths_, from, to, walk_, plausible());
    return t && take(*t);
  };
  // A surface path is never shorter than the geodesic; one longer than the
  // O(1) answer plus that answer's bound has settled in a wrong corridor
  // (round the wrong side of a feature). Under a tolerance it is answered
  // exactly. Needs the calibration (else the bound is NaN and no path is
  // doubted).
  auto wrong_corridor = [&] {
    return (kind == AnswerKind::kTrace || kind == AnswerKind::kWrappedTrace) &&
           d > unfolded + bound_of(AnswerKind::kUnfold, unfolded);
  };
  if (near || MayBeNear(unfolded, RefineBelow(options), p, q)) {
    switch (options.near_pairs) {
      case NearPairs::kPath:
        near_path();
        break;
      case NearPairs::kExact:
        exact();
        break;
      case NearPairs::kUnfold:
        break;
    }
  }
  if (options.tolerance > 0) {
    auto within = [&] { return bound_of(kind, d) <= options.tolerance * d; };
    if (kind != AnswerKind::kExact && (!within() || wrong_corridor())) exact();
  }
  if (bound != nullptr) {
    *bound = bound_of(kind, d);
    // A path's own certificate, where it is the tighter: d - chord covers
    // its error whatever the calibration saw (no less than rounding).
    if (kind == AnswerKind::kTrace || kind == AnswerKind::kWrappedTrace) {
      // Beyond the index's own threshold the traces' calibration did not
      // see these paths: the geodesic is at least the chord and at least
      // the O(1) answer less its bound, so d less the larger covers it
      // wherever the O(1) bound does. A path shorter than that floor shows
      // the O(1) bound wrong for this pair (it covers about 99% of them):
      // then only the chord is left to stand on.
      const double o1_floor = unfolded - bound_of(AnswerKind::kUnfold, unfolded);
      const double below = raised_only && d >= o1_floor ? std::max(floor, o1_floor) : floor;
      const double certificate = std::max(d - below, bound_of(AnswerKind::kExact, d));
      *bound = raised_only ? certificate : std::min(*bound, certificate);
    }
  }
  return d;
}

}  // namespace geodex::query
