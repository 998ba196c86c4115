#pragma once

// Accuracy measurement of the query engine against the exact geodesic engine
// on area-uniform random surface point pairs.
//
// Relative error e = (approx - exact) / exact per pair; reported as relative
// RMS = sqrt(mean(e^2)), mean |e|, p99 |e| and max |e|: over area-uniform
// pairs (all, and the far ones), and over near pairs (the same or adjacent
// geodesic triangles), which uniform pairs rarely are, so they are drawn on
// purpose: area-uniform points of the faces of each source's geodesic
// triangle and its neighbours; for each way of answering near pairs
// (query::NearPairs: the pure O(1) unfolding, the path length, the local
// exact propagation) and the paper's linear interpolation baseline (§6.3);
// and path length / exact distance.

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/query_engine.h"

namespace geodex::accuracy {

struct ErrorStats {
  int64_t count = 0;
  double rms = 0, mean = 0, p99 = 0, max = 0;
  static ErrorStats Of(std::vector<double> errors);  // relative errors (signed)
};

struct AccuracyReport {
  // all, far, all_*_mode, baseline: area-uniform pairs; near, near_*_mode:
  // the near pairs drawn on purpose and the uniform ones that happen to be
  // near. all, far and near are the pure O(1) mode (NearPairs::kUnfold); far
  // pairs are the same in every mode.
  ErrorStats all, far, near, baseline, path_ratio;
  ErrorStats near_path_mode, all_path_mode;    // NearPairs::kPath (the default)
  ErrorStats near_exact_mode, all_exact_mode;  // NearPairs::kExact
  ErrorStats traced_path_ratio;                // the gradient trace before straightening
  std::string ToMarkdownRow(const std::string& label) const;
  static std::string MarkdownHeader();
};

struct AccuracyOptions {
  int32_t num_points = 400;      // random points; pairs are (source, point)
  int32_t num_sources = 20;      // exact propagations
  int32_t num_paths = 100;       // pairs whose path length is measured
  int32_t num_near_points = 40;  // near points drawn per source
  uint64_t seed = 1;
};

// Area-uniform random surface points.
std::vector<mesh::SurfacePoint> RandomSurfacePoints(const mesh::Mesh& mesh, int32_t count,
                                                    uint64_t seed);

// One engine per way of answering near pairs, over the same index.
struct Engines {
  std::shared_ptr<const query::QueryEngine> unfold, path, exact;
};
// `base` gives every option but near_pairs.
absl::StatusOr<Engines> MakeEngines(std::shared_ptr<const index::Index> index,
                                    query::QueryOptions base = {});

// The engines must be built from an index of `mesh`.
AccuracyReport MeasureAccuracy(const mesh::Mesh& mesh, const Engines& engines,
                               const AccuracyOptions& options);

}  // namespace geodex::accuracy
