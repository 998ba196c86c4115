#pragma once

// The refined answers of one index against the exact engine, for
// query_bench: what near pairs and tolerances cost and how close they come.
//
// Near pairs are drawn round random points (the other point a random walk
// of a few faces away), binned by their O(1) distance in units of the
// index's L, vertex and interior points apart; each row gives the default
// mode's batch rate with bounds, the |relative error|'s p99 and maximum,
// the share of answers within their bound and the share answered exactly.
// Tolerance rows refine area-uniform interior pairs. The reference is the
// whole-mesh window engine (core/geodesic/exact_geodesic.h) on the index's
// mesh, stopped at the second point: not the confined solver the answers
// use.
//
// Not thread-safe; rates are per CPU-second of the calling thread.

#include <cstddef>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/index/index.h"
#include "core/mesh/mesh.h"

namespace geodex::bench {

// A uniform random point of `face`, or one of its corners when `vertex`.
mesh::SurfacePoint RandomPoint(int32_t face, bool vertex, std::mt19937_64& rng);

struct AccuracyRow {
  std::string pairs;  // e.g. "interior L-3L" or "uniform, tolerance 0.005"
  size_t count = 0;   // pairs measured
  double rate = 0;    // batch pairs/s with the row's options and bounds
  double p99 = 0;     // |relative error|
  double p999 = 0;
  double max = 0;
  double coverage = 0;     // share with |error| <= bound
  double exact_share = 0;  // share answered exactly (a rounding-sized bound)
};

// The rows of `ix` (which needs its accuracy calibration), at most
// `per_row` pairs each: the default mode per scale bin, vertex then
// interior, then tolerances 0.005 and 0.001 on area-uniform pairs.
std::vector<AccuracyRow> MeasureRefinementAccuracy(std::shared_ptr<const index::Index> ix,
                                                   int per_row);

// The table's title and header, and one row (no newline).
std::string AccuracyHeader();
std::string AccuracyRowText(const std::string& label, const AccuracyRow& row);

}  // namespace geodex::bench
