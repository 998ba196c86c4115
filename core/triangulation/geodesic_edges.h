#pragma once

// The edges of the geodesic Delaunay triangulation realised as exact
// geodesics (paper §4.1: "each Delaunay edge is replaced by an exact geodesic
// between its two samples"), and the check that together they embed the
// triangulation in the surface: no two of them may cross or touch anywhere
// but at a sample they share.
//
// Example:
//   auto edges = TraceEdges(mesh, samples, dual.triangles, /*threads=*/2);
//   auto crossings = FindCrossings(mesh, samples, *edges);
//
// Thread safety: the functions are reentrant.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"

namespace geodex::triangulation {

// One Delaunay edge traced on the surface.
struct GeodesicEdge {
  int32_t a = 0;  // samples, a < b
  int32_t b = 0;
  double distance = 0;  // d(a, b) from the exact propagation from a
  double length = 0;    // length of `path`: equals `distance` up to rounding
  // The shortest geodesic from the vertex of sample a to that of sample b: the
  // two ends and every mesh edge crossing and vertex in between, in order;
  // consecutive points lie in a common face and are distinct places.
  std::vector<mesh::SurfacePoint> path;
};

// The undirected edges of `triangles` (sample triples) as pairs (a, b) with
// a < b, sorted, each once.
std::vector<std::pair<int32_t, int32_t>> DelaunayEdges(
    std::span<const std::array<int32_t, 3>> triangles);

// Traces every edge of `triangles` as the exact shortest geodesic between the
// vertices of its samples (`samples[i]` is the vertex of sample i). Runs one
// exact propagation per sample a that has a neighbour b > a, stopped as soon
// as the distances to all those neighbours are final (so each is local), then
// follows the path back from each b; the samples are shared among `threads`
// worker threads (0: all hardware threads). Samples joined by a mesh edge no
// longer than their distance are joined by that edge, whichever equally short
// path the propagation would take (through the apex of a zero-area face on
// the edge, or across the other layer of a fold pressed flat). The result is
// sorted by (a, b) and identical for every thread count.
// Errors: InvalidArgument for a sample id or vertex out of range; NotFound when
// two adjacent samples are not connected on the surface; errors of the
// geodesic engine.
absl::StatusOr<std::vector<GeodesicEdge>> TraceEdges(
    const mesh::Mesh& mesh, std::span<const int32_t> samples,
    std::span<const std::array<int32_t, 3>> triangles, int threads = 1);

// Two geodesic edges that meet away from their common sample.
struct EdgeCrossing {
  int32_t first = 0;  // indices into the edges, first < second
  int32_t second = 0;
  mesh::SurfacePoint point;  // a place where they meet
};

// Points closer than this fraction of a face's longest side count as touching.
inline constexpr double kTouchTolerance = 1e-9;

// Every pair of `edges` whose paths cross or touch anywhere other than at a
// sample that both end at (`samples[i]` is the vertex of sample i), once per
// pair, sorted by (first, second). Paths are cut into per-face pieces and
// compared face by face in that face's own planar frame, within
// kTouchTolerance; a zero-area or sliver face, whose frame is a segment, by
// the pieces' barycentric coordinates (in an equilateral triangle). A path
// point on a mesh edge or vertex belongs to every face around it, so two
// paths that pass through the same mesh vertex touch; so does a path passing
// through the vertex of a sample it does not end at. Two edges ending at the
// same sample touch there only if they leave it in the same direction.
// Errors: InvalidArgument for an invalid path point, a sample id out of range,
// or two consecutive points with no face in common.
absl::StatusOr<std::vector<EdgeCrossing>> FindCrossings(const mesh::Mesh& mesh,
                                                        std::span<const int32_t> samples,
                                                        std::span<const GeodesicEdge> edges);

// Figures about a set of traced edges.
struct EdgeStats {
  int32_t count = 0;
  double total_length = 0;
  double longest = 0;
  // max |length - distance| / distance over the edges.
  double max_relative_error = 0;
};
EdgeStats SummarizeEdges(std::span<const GeodesicEdge> edges);

// The paths as Wavefront OBJ polylines (a `v` line per path point, an `l` line
// per edge), for viewing next to the mesh.
std::string EdgesToObj(const mesh::Mesh& mesh, std::span<const GeodesicEdge> edges);

}  // namespace geodex::triangulation
