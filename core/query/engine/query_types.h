#pragma once

// The value types of geodex's queries: how a distance is asked for
// (DistanceOptions, NearPairs), how the queries of an index are set up
// (QueryOptions), the options of a field within a radius, and what comes
// back (PathPoint, DistanceField, RadiusField, LocatedPoint). Plain data: the
// public face of core/query with input_queries.h and query_scratch.h. A
// query that is a part of its own keeps its types in its own header beside
// them.

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "core/mesh/mesh.h"

namespace geodex::query {

using mesh::SurfacePoint;

// The distance between points of different components.
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// How Distance and DistanceBatch answer the pairs they refine by default:
// near pairs (points in the same or adjacent geodesic triangles) and pairs
// that may be closer than kRefineScale * scale_length(): their O(1) distance
// is below it, or, in a calibrated index, below it plus the error bound of
// O(1) answers just beyond it.
enum class NearPairs {
  // Pure O(1): the unfolding of §5, for near pairs kept at least the
  // straight-line distance apart (no surface path is shorter). Nothing is
  // refined.
  kUnfold,
  // The length of the straightened gradient trace of p's field, and of
  // q's when that one wraps round a vertex (Path without its restarts, so
  // Path can be shorter): a surface path, never below the geodesic
  // distance; O(k) in the faces it crosses. With straighten_paths off, the
  // raw traces (longer).
  kPath,
  // A local exact propagation from one point that stops when it reaches the
  // other.
  kExact,
};

// Pairs whose O(1) distance is below this many scale lengths are refined by
// default. The bins of §6.5's weak spot: the O(1) answer's relative error
// grows fastest below 3L, where a trace crosses few faces.
inline constexpr double kRefineScale = 3;

// Per-call choices of Distance and DistanceBatch.
struct DistanceOptions {
  NearPairs near_pairs = NearPairs::kPath;
  // Relative error tolerance. > 0: every pair whose error bound exceeds
  // tolerance x distance is refined further, by the straightened trace and
  // then by a local exact propagation (bound 0), so that its bound meets the
  // tolerance. Needs the index's accuracy calibration.
  double tolerance = 0;
  // > 0: also refine, as near_pairs says, every pair that may be closer
  // than this many L1000 (the spacing of 1,000 samples on the surface,
  // sqrt(2A / (sqrt(3) 1000)): a unit fixed by the surface, not by the
  // index's m). It raises the default threshold, never lowers it. Raised to
  // where the index's O(1) answer is good enough (its build report gives
  // the p99 by band of L1000), every answer is walked, exact or such an
  // O(1) answer: the every-distance mode (tests/bench/accuracy.md). 0: the
  // index's own threshold.
  double refine_below_l1000 = 0;
};

struct QueryOptions {
  // When > 0, Path also solves exactly (the ICH engine) inside a corridor
  // round the traced path, the faces at most this many edge steps from the
  // faces it crosses, and returns the exact path when it is shorter. This
  // finds the side of a bump that a trace of the approximate field can miss;
  // it costs a propagation over the corridor (not O(k)). 0: off.
  int32_t exact_path_corridor = 0;
  // Barycentric tolerance for validation (weights >= -tol, |sum - 1| <= tol).
  double weight_tolerance = 1e-6;
};

struct PathPoint {
  SurfacePoint point;
  mesh::Vec3 position;
};

// The sum of a path's 3D segments: the length every interface reports.
inline double PathLength(std::span<const PathPoint> path) {
  double sum = 0;
  for (size_t i = 1; i < path.size(); ++i) sum += (path[i].position - path[i - 1].position).norm();
  return sum;
}

struct DistanceField {
  std::vector<double> distance;  // per vertex; +inf when unreachable or unreferenced
  std::vector<int32_t> nearest;  // per vertex: index of the nearest source (-1 if none)
};

// How a distance field within a radius is asked for (InputQueries::
// FieldWithin).
struct FieldWithinOptions {
  // Vertices farther than this from every source are left out; finite, > 0.
  double radius = 0;
  // When > 0, the most vertices the propagation may reach (those within the
  // radius and a ring beyond): more is ResourceExhausted, and the work stops
  // there. 0: no limit.
  int64_t max_vertices = 0;
};

// The exact distance field within a radius: entry i is vertex vertices[i]
// (ascending), at geodesic distance distance[i] <= radius from its nearest
// source, the nearest[i]-th. Only vertices within the radius are listed.
struct RadiusField {
  std::vector<int32_t> vertices;
  std::vector<double> distance;
  std::vector<int32_t> nearest;
};

struct LocatedPoint {
  SurfacePoint point;   // face + barycentric weights (>= 0, sum 1)
  double distance = 0;  // Euclidean distance from the query to the surface
};

}  // namespace geodex::query
