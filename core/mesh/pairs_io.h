#pragma once

// The point-pair text format shared by geodex-geodesic, geodex-query and the
// `geodex` client CLI: one pair per line,
//
//   fa a0 a1 a2 fb b0 b1 b2
//
// the face id and the barycentric weights of that face's three vertices (in
// file order) for point A, then the same for point B. Either point may be
// given as "v ID" instead, a vertex id of the mesh file ("v 17 v 42",
// "v 17 3 0.2 0.3 0.5"): the vertex in the lowest face that holds it.
// Blank lines and lines starting with '#' are skipped and produce no
// output.

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"

namespace geodex::mesh {

struct PointPair {
  SurfacePoint a;
  SurfacePoint b;
  int64_t line = 0;  // 1-based line number in the input
  // The vertex ids of a and b when given as "v ID" (else kNone): ParsePairs
  // leaves such a point for ResolveVertices to fill in.
  std::array<int32_t, 2> vertex = {kNone, kNone};
};

// Parses every line. Errors: InvalidArgument naming the first bad line (wrong
// field count, not a number, non-finite value, not a vertex id). Point
// validity against a mesh is checked by ValidatePairs.
absl::StatusOr<std::vector<PointPair>> ParsePairs(std::string_view contents);

// Fills in the points given as vertex ids with `vertex_point` (the vertex's
// point in a face of the mesh the pairs are about). Errors: vertex_point's,
// prefixed with "line N: ".
absl::Status ResolveVertices(const std::function<absl::StatusOr<SurfacePoint>(int32_t)>& vertex_point,
                             std::vector<PointPair>* pairs);

// Per vertex of `mesh`, weight 1 on it in the lowest face holding it (face
// kNone for a vertex no face uses); VertexPointOf reads it with the errors of
// a vertex id: OutOfRange past the end, InvalidArgument on no face.
std::vector<SurfacePoint> LowestFacePoints(const Mesh& mesh);
absl::StatusOr<SurfacePoint> VertexPointOf(std::span<const SurfacePoint> lowest_face_points,
                                           int32_t v);

// Checks both points of every pair against `mesh` (ValidateSurfacePoint).
// Errors: the first failure, its message prefixed with "line N: ".
absl::Status ValidatePairs(const Mesh& mesh, const std::vector<PointPair>& pairs);

// A line of numbers (ParseNumberLines).
struct NumberLine {
  std::vector<double> values;
  int64_t line = 0;  // 1-based line number in the input
};

// Parses lines of exactly `width` finite numbers each (separated as pairs
// are), skipping blank and '#' lines: source points "f w0 w1 w2", positions
// "x y z". Errors: InvalidArgument naming the first bad line.
absl::StatusOr<std::vector<NumberLine>> ParseNumberLines(std::string_view contents, size_t width);

// Reads a whole file (ReadWholeFile, with its errors), or standard input for
// "-".
absl::StatusOr<std::string> ReadFileOrStdin(const std::string& path);

// Formats a distance as printed by the tools: shortest round-trip decimal,
// "inf" when unreachable.
std::string FormatDistance(double d);

}  // namespace geodex::mesh
