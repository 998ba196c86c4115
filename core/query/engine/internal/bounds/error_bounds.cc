#include "core/query/engine/internal/bounds/error_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"

namespace geodex::query {

ErrorBounds::ErrorBounds(const index::Index& index)
    : accuracy_(index.accuracy()), spread_(index.spread_bounds()) {}

double ErrorBounds::Of(AnswerKind kind, bool vertex_pair, double d, double spread) const {
  if (accuracy_ == nullptr) return std::numeric_limits<double>::quiet_NaN();
  if (!(d < std::numeric_limits<double>::infinity())) return 0;
  if (kind == AnswerKind::kExact) return kExactRelativeBound * d;
  const double x = d / accuracy_->scale_length;
  int b = 0;
  while (b + 1 < index::kAccuracyBins && x >= index::kAccuracyBinUpper[b]) ++b;
  const int k = vertex_pair ? 0 : 1;
  switch (kind) {
    case AnswerKind::kUnfold:
      if (spread_ != nullptr && spread_->factor[k][b] > 0) {
        return spread_->factor[k][b] * (spread + spread_->epsilon[k][b] * d);
      }
      return accuracy_->unfold_bound[k][b];
    case AnswerKind::kTrace:
      return accuracy_->trace_bound[vertex_pair ? 2 : 0][b];
    case AnswerKind::kWrappedTrace:
      return accuracy_->trace_bound[vertex_pair ? 3 : 1][b];
    case AnswerKind::kExact:
      break;
  }
  return 0;
}

double ErrorBounds::RefineMargin() const {
  if (accuracy_ == nullptr) return 0;
  constexpr int kBin = 4;  // [3L, 5L)
  static_assert(index::kAccuracyBinUpper[kBin - 1] == kRefineScale);
  const double margin =
      std::max(accuracy_->unfold_bound[0][kBin], accuracy_->unfold_bound[1][kBin]);
  return margin > 0 && std::isfinite(margin) ? margin : 0;
}

absl::Status ErrorBounds::CheckOptions(const DistanceOptions& options, bool bounds) const {
  if (!(options.tolerance >= 0) || !std::isfinite(options.tolerance)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tolerance must be finite and >= 0, not %g", options.tolerance));
  }
  if (!(options.refine_below_l1000 >= 0) || !std::isfinite(options.refine_below_l1000)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "refine_below_l1000 must be finite and >= 0, not %g", options.refine_below_l1000));
  }
  if ((bounds || options.tolerance > 0) && accuracy_ == nullptr) {
    return absl::FailedPreconditionError(
        "the index has no accuracy calibration (error bounds, tolerance): rebuild it, or add one "
        "with geodex-build calibrate");
  }
  return absl::OkStatus();
}

}  // namespace geodex::query
