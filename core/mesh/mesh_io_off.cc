// OFF reader (mesh_io.h).

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_io_text.h"

namespace geodex::mesh {
namespace {

using io_internal::FanTriangulateRaw;
using io_internal::LineError;
using io_internal::LineReader;
using io_internal::ParseCoordinates;
using io_internal::ParseInt;
using io_internal::Quote;
using io_internal::StripComment;
using io_internal::Tokens;

// OFF (Geomview's Object File Format, as also written by libigl and CGAL).

// Returns true for OFF header keywords whose vertex lines start with x y z:
// OFF and its colour/normal/texture variants. 4OFF / nOFF change the
// dimension and are not supported.
bool IsOffKeyword(std::string_view keyword) {
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF") return false;
  std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.starts_with("ST")) prefix.remove_prefix(2);
  if (prefix.starts_with("C")) prefix.remove_prefix(1);
  if (prefix.starts_with("N")) prefix.remove_prefix(1);
  return prefix.empty();
}

// The lines of an OFF file that have content, as tokens, comments removed.
class OffLines {
 public:
  explicit OffLines(std::string_view contents) : reader_(contents) {}

  // The next line's tokens; false at the end of the file.
  bool Next(std::vector<std::string_view>* tokens) {
    std::string_view line;
    while (reader_.Next(&line)) {
      *tokens = Tokens(StripComment(line));
      if (!tokens->empty()) return true;
    }
    return false;
  }
  // Number of the line last read.
  int64_t line() const { return reader_.line(); }
  // Bytes not yet read.
  size_t remaining() const { return reader_.remaining(); }

 private:
  LineReader reader_;
};

struct OffCounts {
  int64_t num_vertices = 0;
  int64_t num_faces = 0;
};

// The keyword and the counts line.
absl::StatusOr<OffCounts> ReadOffHeader(OffLines& in, const std::string& name) {
  std::vector<std::string_view> tokens;
  if (!in.Next(&tokens)) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": empty OFF file"));
  }
  if (!IsOffKeyword(tokens[0])) {
    return LineError(name, in.line(),
                     absl::StrCat("not an OFF file: expected 'OFF', found ", Quote(tokens[0])));
  }
  if (tokens.size() > 1 && tokens[1] == "BINARY") {
    return LineError(name, in.line(), "binary OFF is not supported");
  }
  // The counts may follow the keyword on the same line.
  tokens.erase(tokens.begin());
  if (tokens.empty() && !in.Next(&tokens)) {
    return LineError(name, in.line() + 1, "file ends before the counts line");
  }
  int64_t num_vertices = 0, num_faces = 0, num_edges = 0;
  if (tokens.size() < 2 || tokens.size() > 3 || !ParseInt(tokens[0], &num_vertices) ||
      !ParseInt(tokens[1], &num_faces) ||
      (tokens.size() == 3 && !ParseInt(tokens[2], &num_edges)) || num_vertices < 0 ||
      num_faces < 0) {
    return LineError(name, in.line(),
                     "expected the counts line '<vertices> <faces> [<edges>]' (integers >= 0)");
  }
  // Each vertex and face needs at least one line of at least two bytes.
  if (num_vertices > std::numeric_limits<int32_t>::max() - 1 ||
      num_faces > std::numeric_limits<int32_t>::max() ||
      num_vertices + num_faces > static_cast<int64_t>(in.remaining() / 2 + 1)) {
    return LineError(name, in.line(),
                     absl::StrFormat("counts (%d vertices, %d faces) exceed the %d bytes left in "
                                     "the file",
                                     num_vertices, num_faces, in.remaining()));
  }
  return OffCounts{num_vertices, num_faces};
}

absl::StatusOr<std::vector<Vec3>> ReadOffVertices(OffLines& in, const std::string& name,
                                                  int64_t num_vertices) {
  std::vector<std::string_view> tokens;
  std::vector<Vec3> positions;
  positions.reserve(num_vertices);
  for (int64_t v = 0; v < num_vertices; ++v) {
    if (!in.Next(&tokens)) {
      return LineError(name, in.line() + 1,
                       absl::StrFormat("file ends before vertex %d of %d (truncated file, or the "
                                       "header count is too large)",
                                       v, num_vertices));
    }
    if (tokens.size() < 3) {
      return LineError(name, in.line(),
                       absl::StrFormat("vertex has %d coordinates, expected 3", tokens.size()));
    }
    // Values after x y z (colours, normals, texture coordinates) are ignored.
    Vec3 p;
    GEODEX_RETURN_IF_ERROR(ParseCoordinates(tokens, name, in.line(), &p));
    positions.push_back(p);
  }
  return positions;
}

// Appends the corners of the face on line `line`, `tokens`, to `corners`.
absl::Status ParseOffFace(std::span<const std::string_view> tokens, const std::string& name,
                          int64_t line, int64_t num_vertices, std::vector<int32_t>& corners) {
  int64_t k = 0;
  if (!ParseInt(tokens[0], &k)) {
    return LineError(name, line,
                     absl::StrCat("face corner count ", Quote(tokens[0]), " is not an integer"));
  }
  if (k < 3) {
    return LineError(name, line, absl::StrFormat("face has %d corners, at least 3 needed", k));
  }
  if (k > static_cast<int64_t>(tokens.size()) - 1) {
    return LineError(
        name, line,
        absl::StrFormat("face declares %d corners but lists %d values", k, tokens.size() - 1));
  }
  // Values after the k indices (a face colour) are ignored.
  for (int64_t i = 1; i <= k; ++i) {
    int64_t index = 0;
    if (!ParseInt(tokens[i], &index)) {
      return LineError(name, line,
                       absl::StrCat("vertex index ", Quote(tokens[i]), " is not an integer"));
    }
    if (index < 0 || index >= num_vertices) {
      return LineError(name, line,
                       absl::StrFormat("vertex index %d is out of range (the file has %d "
                                       "vertices)",
                                       index, num_vertices));
    }
    corners.push_back(static_cast<int32_t>(index));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<RawMesh> ParseOffTriangles(std::string_view contents, const std::string& name) {
  OffLines in(contents);
  GEODEX_ASSIGN_OR_RETURN(const OffCounts counts, ReadOffHeader(in, name));
  GEODEX_ASSIGN_OR_RETURN(std::vector<Vec3> positions,
                          ReadOffVertices(in, name, counts.num_vertices));
  std::vector<std::string_view> tokens;
  std::vector<int32_t> corners;
  std::vector<size_t> face_begin = {0};
  face_begin.reserve(counts.num_faces + 1);
  for (int64_t f = 0; f < counts.num_faces; ++f) {
    if (!in.Next(&tokens)) {
      return LineError(name, in.line() + 1,
                       absl::StrFormat("file ends before face %d of %d (truncated file, or the "
                                       "header count is too large)",
                                       f, counts.num_faces));
    }
    GEODEX_RETURN_IF_ERROR(ParseOffFace(tokens, name, in.line(), counts.num_vertices, corners));
    face_begin.push_back(corners.size());
  }
  if (in.Next(&tokens)) {
    return LineError(name, in.line(),
                     "unexpected data after the last face (the header counts do not match the "
                     "data)");
  }
  return FanTriangulateRaw(std::move(positions), corners, face_begin, name);
}

}  // namespace geodex::mesh
