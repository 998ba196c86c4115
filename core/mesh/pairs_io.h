#pragma once

// The point-pair text format shared by geodex-geodesic, geodex-query and the
// `geodex` client CLI: one pair per line,
//
//   fa a0 a1 a2 fb b0 b1 b2
//
// the face id and the barycentric weights of that face's three vertices (in
// file order) for point A, then the same for point B. Blank lines and lines
// starting with '#' are skipped and produce no output.

#include <cstdint>
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
};

// Parses every line. Errors: InvalidArgument naming the first bad line (wrong
// field count, not a number, non-finite value). Point validity against a mesh
// is checked by ValidatePairs.
absl::StatusOr<std::vector<PointPair>> ParsePairs(std::string_view contents);

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
