#pragma once

// Error bounds of answers (Xin, Ying & He 2012, §6.5, made a promise): an
// index built with its accuracy calibration (index::AccuracyRecord) gives
// every answer an absolute error bound, the error its kind of answer (O(1),
// traced, exact) at its distance stayed within on all but a small share of
// held-out exact pairs; rounding for exact answers. With the spread bounds
// (index::SpreadBoundRecord), an O(1) answer's bound also grows with its
// unfolding spread (LiftedUnfolding::Spread), which flags the pairs it errs most on.
//
// Thread safety: immutable; every method is const and thread-safe.

#include "absl/status/status.h"
#include "core/index/index.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

// How an answer was obtained, for its bound.
enum class AnswerKind { kUnfold, kTrace, kWrappedTrace, kExact };

// The bound of an exact answer, relative to it: window propagations agree
// with each other to ~1e-15 relative (a confined one with the whole mesh's,
// the index's mesh with its long edges split with the input mesh); a
// rounding-sized bound, not 0, so that coverage measured against another
// exact solver is honest.
inline constexpr double kExactRelativeBound = 1e-9;

class ErrorBounds {
 public:
  // Over `index`'s calibration (none: no bounds), which must outlive this.
  explicit ErrorBounds(const index::Index& index);

  // True when the index carries its accuracy calibration.
  bool available() const { return accuracy_ != nullptr; }
  // True when O(1) bounds scale with the unfolding spread.
  bool has_spread() const { return spread_ != nullptr; }

  // The bound of an answer of `kind` at distance d between two vertices
  // (`vertex_pair`) or other points; NaN without calibration,
  // kExactRelativeBound x d for exact answers, 0 for unreachable pairs. `spread` scales an O(1)
  // answer's bound when the index has spread bounds.
  double Of(AnswerKind kind, bool vertex_pair, double d, double spread = 0) const;

  // How far beyond 3L an O(1) answer may lie while the pair is closer: the
  // bound of O(1) answers between 3L and 5L (0 without calibration).
  double RefineMargin() const;

  // InvalidArgument for a tolerance that is not finite and >= 0;
  // FailedPrecondition when bounds or a tolerance are asked of an index
  // without calibration.
  absl::Status CheckOptions(const DistanceOptions& options, bool bounds) const;

 private:
  const index::AccuracyRecord* accuracy_;
  const index::SpreadBoundRecord* spread_;
};

}  // namespace geodex::query
