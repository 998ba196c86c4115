#pragma once

// Text input of the `geodex` CLI. The pair format is the one geodex-query and
// geodex-geodesic read (core/mesh/pairs_io.h), re-implemented here because the
// client must not depend on core:
//
//   pairs      fa a0 a1 a2 fb b0 b1 b2   (face id and barycentric weights of A, then B)
//   xyz pairs  xa ya za xb yb zb         (`geodex distance --xyz`)
//   points     f w0 w1 w2                (sources of `geodex field`)
//   positions  x y z                     (`geodex locate`)
//
// In pairs and points, a point may be given as "v ID" instead, a vertex id
// of the mesh file: "v 17 v 42" is the pair of vertices 17 and 42, and
// "v 17 3 0.2 0.3 0.5" pairs vertex 17 with a point of face 3.
//
// Fields are separated by spaces, tabs or commas. Blank lines and lines
// starting with '#' are skipped. Errors name the 1-based line.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "geodex/client/types.h"

namespace geodex::client::cli {

// Whole file, or standard input for "-". Errors: NOT_FOUND.
absl::StatusOr<std::string> ReadFileOrStdin(const std::string& path);

// Writes `contents` to `path` ('-': standard output). A file is written
// beside its name and renamed into place, so that a reader (or a killed run)
// never sees half of it. Errors: ResourceExhausted on a full disk or quota,
// PermissionDenied otherwise (with the system's reason); DataLoss when
// standard output fails.
absl::Status WriteFileOrStdout(const std::string& path, const std::string& contents);

// Surface-point pairs, and the line each came from. Errors: INVALID_ARGUMENT
// naming the first bad line (field count, not a number, not finite, face id
// not a non-negative 32-bit integer).
struct ParsedPairs {
  std::vector<PointPair> pairs;
  std::vector<int64_t> lines;
};
absl::StatusOr<ParsedPairs> ParsePairs(std::string_view text);

// Position pairs "xa ya za xb yb zb".
struct ParsedPositionPairs {
  std::vector<Position> a, b;
  std::vector<int64_t> lines;
};
absl::StatusOr<ParsedPositionPairs> ParsePositionPairs(std::string_view text);

// Surface points "f w0 w1 w2".
struct ParsedPoints {
  std::vector<SurfacePoint> points;
  std::vector<int64_t> lines;
};
absl::StatusOr<ParsedPoints> ParsePoints(std::string_view text);

// Positions "x y z".
struct ParsedPositions {
  std::vector<Position> positions;
  std::vector<int64_t> lines;
};
absl::StatusOr<ParsedPositions> ParsePositions(std::string_view text);

// Checks a point against a model with `num_faces` faces, with the server's
// rules (face id in range; weights >= -1e-6 summing to 1 within 1e-6), so that
// bad input is reported with its line before anything is sent. Errors:
// OUT_OF_RANGE (face), INVALID_ARGUMENT (weights), prefixed "line N: ".
absl::Status CheckPoint(const SurfacePoint& p, int64_t num_faces, int64_t line);

// Shortest round-trip decimal; "inf" when unreachable (as geodex-query).
std::string FormatDistance(double d);

// One line "fa a0 a1 a2 fb b0 b1 b2" per pair, weights in shortest
// round-trip decimals: what ParsePairs (and geodex-query --pairs) read back
// to the same bits.
std::string FormatPairs(const std::vector<PointPair>& pairs);

}  // namespace geodex::client::cli
