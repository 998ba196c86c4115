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

// One pair's refinement: the answer so far, its kind, the best lower bound
// on the geodesic known, and the steps that may improve them.
class Refiner::Pair {
 public:
  // `p`, `q`: canonical points in their lowest faces; `unfolded` finite.
  Pair(const Refiner& refiner, const SurfacePoint& p, const SurfacePoint& q, const LiftedPoint& lp,
       const LiftedPoint& lq, double unfolded, bool near, QueryScratch& solvers)
      : r_(refiner),
        // The refinements work from one point to the other: from the
        // smaller, so that the answer is symmetric.
        from_(std::tie(q.face, q.w) < std::tie(p.face, p.w) ? q : p),
        to_(std::tie(q.face, q.w) < std::tie(p.face, p.w) ? p : q),
        lp_(lp),
        lq_(lq),
        unfolded_(unfolded),
        vertex_pair_(AtVertex(p) && AtVertex(q)),
        chord_((r_.view_.PositionOf(p) - r_.view_.PositionOf(q)).norm()),
        // A pair refined only because the request raised the threshold
        // past the index's own (DistanceOptions::refine_below_l1000) is
        // beyond the band where the chord certifies walks: on a curved
        // surface most of its walks are more than 2% longer than the chord.
        // There a walk the corridor vouches for, no longer than the O(1)
        // answer plus its bound, is taken as it is (a wrong corridor's walk
        // is mostly longer than that), and a pair whose walks all fail keeps
        // its O(1) answer: the mode's promise is p99 in every band, not the
        // near pairs' largest error (tests/bench/accuracy.md, "The
        // every-distance mode").
        raised_only_(!near && !r_.MayBeNear(unfolded, r_.refine_below_, p, q)),
        solvers_(solvers),
        stats_(solvers.near_pair_stats()),
        d_(near ? std::max(unfolded, chord_) : unfolded),
        floor_(chord_) {}

  // The answer under `options`, its bound in *bound when not null.
  double Answer(bool near, const DistanceOptions& options, double* bound) {
    if (near || r_.MayBeNear(unfolded_, r_.RefineBelow(options), from_, to_)) {
      switch (options.near_pairs) {
        case NearPairs::kPath:
          Walked();
          break;
        case NearPairs::kExact:
          Exact();
          break;
        case NearPairs::kUnfold:
          break;
      }
    }
    if (options.tolerance > 0 && kind_ != AnswerKind::kExact &&
        (!(BoundOf(kind_, d_) <= options.tolerance * d_) || WrongCorridor())) {
      Exact();
    }
    if (bound != nullptr) *bound = Bound();
    return d_;
  }

 private:
  static bool AtVertex(const SurfacePoint& x) {
    return x.w[0] == 1 || x.w[1] == 1 || x.w[2] == 1;
  }
  bool IsPath() const { return kind_ == AnswerKind::kTrace || kind_ == AnswerKind::kWrappedTrace; }

  // The bound of an answer; the spread of an O(1) answer is computed once,
  // when first needed.
  double BoundOf(AnswerKind k, double at) {
    if (k == AnswerKind::kUnfold && !spread_) {
      spread_ = r_.bounds_.has_spread() ? r_.unfolding_.Spread(lp_, lq_, unfolded_) : 0;
    }
    return r_.bounds_.Of(k, vertex_pair_, at, spread_.value_or(0));
  }

  // The O(1) answer plus its bound: a straight walk longer than that is
  // doubted (NaN without calibration: none is).
  double Plausible() {
    const double limit = unfolded_ + BoundOf(AnswerKind::kUnfold, unfolded_);
    return std::isnan(limit) ? kInf : limit;
  }

  // Exact answers run a propagation confined to a region round the pair
  // (its cost follows the region), else one over the whole mesh from
  // `from_` that stops at `to_`. `path_length`: the length of a surface path
  // between the points, if known; `seeds`: the faces the region starts from
  // (none: a chain of faces from one point to the other).
  bool Exact(double path_length = kInf, std::span<const int32_t> seeds = {}) {
    std::optional<double> e = r_.exact_.ConfinedDistance(from_, to_, seeds, solvers_, path_length);
    if (!e) e = r_.exact_.NearDistance(from_, to_, &solvers_);
    if (!e) return false;
    d_ = *e;
    kind_ = AnswerKind::kExact;
    return true;
  }

  bool Take(const NearPath& path) {
    d_ = path.length;
    kind_ = path.wraps ? AnswerKind::kWrappedTrace : AnswerKind::kTrace;
    return true;
  }

  // Every surface path, the geodesic too, is at least as long as a lower
  // bound: first the chord |pq|, then, for a path the chord leaves
  // uncertified, the two chords through the border of the faces nearer p
  // (cut_bound.h), which follow a curved surface closer. A path within
  // kCertifiedExcess of the bound errs less than that, whichever corridor
  // it took. A longer walk may be a local geodesic round the wrong side of a
  // sharp edge or a bump, which no calibrated bound sees (the shortest path
  // crosses the feature elsewhere; tests/bench/accuracy.md, "Walks the chord
  // certifies"): it is checked by an exact propagation, which its length
  // prunes from the start.
  bool Certified(double length) {
    if (length <= (1 + kCertifiedExcess) * floor_) return true;
    if (cut_tried_) return false;
    cut_tried_ = true;
    floor_ = std::max(floor_, CutLowerBound(r_.view_, from_, to_, kCutReach * length, kCutFaces,
                                            &solvers_.walks()));
    return length <= (1 + kCertifiedExcess) * floor_;
  }

  // A near pair: the chord's walks find a local geodesic for most; the rest
  // (both walks failed, bent at several saddles, or ran longer than is
  // plausible) are answered exactly, which the gradient trace that used to
  // answer them erred up to 5% at p99 on, in about the same time
  // (tests/bench/exact_geodesics.md). The trace stays for an index whose
  // mesh cannot be rebuilt for exact propagation, and for `walk_` off
  // (benchmarks).
  bool Walked() {
    ++stats_.pairs;
    if (!r_.walk_) return Traced(false);
    // Beyond the index's own threshold geodesics are shot first, aimed as
    // the O(1) field of `to` sees the geodesic leave `from` and held within
    // kShotExcess of the O(1) answer: there the chord's walks mostly fail
    // (the chord leaves the surface) and a trace costs ten shots. Near pairs
    // keep the chord's walks, which settle most of them.
    const NearWalk walk =
        raised_only_ ? WalkNearPair(r_.view_, from_, to_,
                                    {.plausible = Plausible(),
                                     .plausible_shot = (1 + kShotExcess) * unfolded_,
                                     .heading = r_.paths_.Heading(from_, to_),
                                     .shoot = true},
                                    &solvers_)
                     : WalkNearPair(r_.view_, from_, to_, {.plausible = Plausible()}, &solvers_);
    if (walk.path && (raised_only_ || Certified(walk.path->length))) return Take(*walk.path);
    if (raised_only_) return RaisedTraced();
    // A doubted walk (bent at several saddles, or longer than is
    // plausible) is a surface path all the same: within the bound's
    // certificate it is taken.
    if (!walk.path && walk.doubted && Certified(*walk.doubted)) {
      return Take(NearPath{*walk.doubted, true});
    }
    if (CheckedExactly(walk)) return true;
    if (walk.path) return Take(*walk.path);  // a mesh without exact propagation
    return Traced(true);
  }

  // The gradient trace finds the corridor where the chord's does not (the
  // chord leaves the surface over a curved band); a trace longer than is
  // plausible keeps the O(1) answer.
  bool RaisedTraced() {
    ++stats_.traces;
    const std::optional<NearPath> t =
        NearPathLength(r_.view_, r_.paths_, from_, to_, false, Plausible());
    if (t && t->length <= Plausible()) return Take(*t);
    ++stats_.raised_kept;
    return false;
  }

  // `walk_chord`: the chord's walks first.
  bool Traced(bool walk_chord) {
    ++stats_.traces;
    const std::optional<NearPath> t =
        NearPathLength(r_.view_, r_.paths_, from_, to_, walk_chord, Plausible());
    return t && Take(*t);
  }

  // The doubted walk's length prunes the propagation from its first
  // window, and its corridor, where the shortest path mostly runs, is the
  // first region (a chain of faces found by a search round the pair cost
  // more than the propagation in it).
  bool CheckedExactly(const NearWalk& walk) {
    const double upper = walk.path ? walk.path->length : walk.doubted.value_or(kInf);
    const bool solved = Exact(upper, walk.corridor);
    ++stats_.exact_solves;
    stats_.exact_with_walk += walk.path || walk.doubted;
    if (const auto* confined = solvers_.solvers().last_confined) {
      stats_.exact_rounds += confined->stats().rounds;
      stats_.exact_region_faces += confined->stats().region_faces;
      stats_.exact_windows += confined->stats().windows_created;
    }
    return solved;
  }

  // A surface path is never shorter than the geodesic; one longer than the
  // O(1) answer plus that answer's bound has settled in a wrong corridor
  // (round the wrong side of a feature). Under a tolerance it is answered
  // exactly. Needs the calibration (else the bound is NaN and no path is
  // doubted).
  bool WrongCorridor() {
    return IsPath() && d_ > unfolded_ + BoundOf(AnswerKind::kUnfold, unfolded_);
  }

  // The answer's bound: its kind's, or for a path its own certificate,
  // where that is the tighter: d less the best lower bound covers its error
  // whatever the calibration saw (no less than rounding).
  double Bound() {
    const double calibrated = BoundOf(kind_, d_);
    if (!IsPath()) return calibrated;
    // Beyond the index's own threshold the traces' calibration did not see
    // these paths: the geodesic is at least the chord and at least the O(1)
    // answer less its bound, so d less the larger covers it wherever the
    // O(1) bound does. A path shorter than that floor shows the O(1) bound
    // wrong for this pair (it covers about 99% of them): then only the
    // chord is left to stand on.
    const double o1_floor = unfolded_ - BoundOf(AnswerKind::kUnfold, unfolded_);
    const double below = raised_only_ && d_ >= o1_floor ? std::max(floor_, o1_floor) : floor_;
    const double certificate = std::max(d_ - below, BoundOf(AnswerKind::kExact, d_));
    return raised_only_ ? certificate : std::min(calibrated, certificate);
  }

  const Refiner& r_;
  const SurfacePoint& from_;
  const SurfacePoint& to_;
  const LiftedPoint& lp_;
  const LiftedPoint& lq_;
  const double unfolded_;
  const bool vertex_pair_;
  const double chord_;
  const bool raised_only_;
  QueryScratch& solvers_;
  NearPairStats& stats_;
  double d_;
  AnswerKind kind_ = AnswerKind::kUnfold;
  std::optional<double> spread_;
  double floor_;  // the best lower bound on the geodesic known
  bool cut_tried_ = false;
};

double Refiner::Refine(const SurfacePoint& p_in, const SurfacePoint& q_in, const LiftedPoint& lp,
                       const LiftedPoint& lq, double unfolded, bool near,
                       const DistanceOptions& options, QueryScratch* scratch, double* bound) const {
  const SurfacePoint p = view_.InLowestFaceIfVertex(p_in), q = view_.InLowestFaceIfVertex(q_in);
  if (!(unfolded < kInf)) {  // different components: exactly unreachable
    if (bound != nullptr) *bound = bounds_.Of(AnswerKind::kExact, false, unfolded);
    return unfolded;
  }
  QueryScratch own;
  Pair pair(*this, p, q, lp, lq, unfolded, near, scratch != nullptr ? *scratch : own);
  return pair.Answer(near, options, bound);
}

}  // namespace geodex::query
