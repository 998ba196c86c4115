#pragma once

// Accuracy measurement of the query engine against the exact geodesic engine,
// by distance scale: the pairs of core/validation/pair_sampling.h (bins d < L,
// L-3L, 3L-10L, >= 10L; area-uniform pairs and pairs drawn in every bin on
// purpose; vertex pairs and pairs inside faces apart), with a seed other
// than the builder's calibration.
//
// Relative error e = (approx - exact) / exact per pair; reported per bin as
// relative RMS, p99 |e| and max |e|, and, for answers that carry an absolute
// error bound, its coverage (share of pairs with |approx - exact| <= bound),
// the median bound and the 90th percentile of |approx - exact|.

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/query_engine.h"
#include "core/validation/pair_sampling.h"

namespace geodex::accuracy {

using validation::ExactPair;
using validation::kNumScaleBins;
inline constexpr int kNumBins = kNumScaleBins;
const char* BinName(int bin);  // validation::ScaleBinName

struct ErrorStats {
  int64_t count = 0;
  double rms = 0, mean = 0, p99 = 0, max = 0;
  static ErrorStats Of(std::vector<double> errors);  // relative errors (signed)
};

// An answer: a distance and, when the mode gives one, an absolute error bound
// (NaN otherwise).
struct Answer {
  double distance = 0;
  double bound = std::numeric_limits<double>::quiet_NaN();
};
using AnswerFn = std::function<Answer(const mesh::SurfacePoint&, const mesh::SurfacePoint&)>;

struct BinReport {
  ErrorStats error;
  // With bounds: share of pairs within their bound; median bound and 90th
  // percentile of the true absolute error (NaN without bounds).
  double coverage = std::numeric_limits<double>::quiet_NaN();
  double median_bound = std::numeric_limits<double>::quiet_NaN();
  double p90_abs_error = std::numeric_limits<double>::quiet_NaN();
};

using validation::kNumFixedBins;

struct ModeReport {
  std::array<BinReport, kNumBins> vertex, interior, all;
  // By bins of L1000 (pair_sampling.h), a unit fixed by the surface, when
  // Evaluate is given it: what the default target is stated in. `far_*`
  // holds every pair at least 8 L1000 apart.
  std::array<BinReport, kNumFixedBins> fixed_vertex, fixed_interior;
  BinReport far_vertex, far_interior;
  ErrorStats uniform;  // the area-uniform interior pairs only, every scale
  // The bin (over vertex and interior) with the largest p99; its p99.
  int worst_bin = 0;
  double worst_p99 = 0;
};

// `unit`: L1000 in mesh units, for the fixed bins (0: left empty).
ModeReport Evaluate(const std::vector<ExactPair>& pairs, const AnswerFn& answer, double unit = 0);

// Markdown: one row per bin and point kind, then a summary row.
std::string MarkdownHeader();
std::string MarkdownRows(const std::string& label, const ModeReport& report);
// The rows by fixed L1000 bin, then the default target's checks for target
// error `target` (target_error.h: uniform RMS <= E, p99 at least 8 L1000
// apart <= 4E, vertex and interior) as measured here, each marked met or
// not. Same columns as MarkdownHeader.
std::string MarkdownFixedRows(const std::string& label, const ModeReport& report, double target);

// Path length / exact distance - 1 over area-uniform pairs: Path (traced,
// straightened, restarted) and the raw gradient trace.
struct PathReport {
  ErrorStats path, traced;
};
PathReport MeasurePaths(const mesh::Mesh& mesh, const query::QueryEngine& engine,
                        int32_t num_sources, int32_t num_points, uint64_t seed);

}  // namespace geodex::accuracy
