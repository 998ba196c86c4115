#pragma once

// Internal to the mesh readers (mesh_io_obj.cc, mesh_io_ply.cc,
// mesh_io_off.cc): the text helpers they share and the hand-over of parsed
// polygons to Mesh::Create. Not part of the public API; include
// core/mesh/mesh_io.h.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"

namespace geodex::mesh::io_internal {

// InvalidArgument "<name>: line <line>: <message>".
absl::Status LineError(const std::string& name, int64_t line, std::string_view message);

// Splits text into lines ended by "\n", "\r\n" or a lone "\r" (the rule
// tinyobjloader uses, so that both agree on line numbers).
class LineReader {
 public:
  explicit LineReader(std::string_view text, int64_t first_line = 1)
      : text_(text), next_line_(first_line) {}

  // Returns false at the end of the text.
  bool Next(std::string_view* line) {
    if (pos_ >= text_.size()) return false;
    size_t end = pos_;
    while (end < text_.size() && text_[end] != '\n' && text_[end] != '\r') ++end;
    *line = text_.substr(pos_, end - pos_);
    if (end < text_.size() && text_[end] == '\r' && end + 1 < text_.size() &&
        text_[end + 1] == '\n') {
      ++end;
    }
    pos_ = end + 1;
    line_ = next_line_++;
    return true;
  }
  // Number of the line last returned by Next().
  int64_t line() const { return line_; }
  // Bytes not yet returned.
  size_t remaining() const { return pos_ >= text_.size() ? 0 : text_.size() - pos_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  int64_t next_line_;
  int64_t line_ = 0;
};

inline bool IsBlank(char c) { return c == ' ' || c == '\t'; }

// Returns the next whitespace-separated token of `rest` (empty at the end) and
// advances `rest` past it.
std::string_view NextToken(std::string_view& rest);

std::vector<std::string_view> Tokens(std::string_view line);

// `line` up to its first '#'.
std::string_view StripComment(std::string_view line);

bool IsBlankLine(std::string_view line);

// Quotes a token for an error message, shortened and with unprintable bytes
// escaped (the token may come from a binary file).
std::string Quote(std::string_view token);

// Parses a whole token as a double (correctly rounded, unlike tinyobjloader's
// own parser). Accepts a leading '+', "nan" and "inf"; the caller decides
// whether non-finite values are allowed. Values that overflow are rejected;
// values that underflow become 0 or subnormal.
bool ParseDouble(std::string_view token, double* value);

// Parses a whole token as an integer; accepts a leading '+'.
bool ParseInt(std::string_view token, int64_t* value);

// Parses three coordinates; errors name the offending token.
absl::Status ParseCoordinates(std::span<const std::string_view> tokens, const std::string& name,
                              int64_t line, Vec3* p);

// Fan-triangulates the parsed polygons (face f has the corners
// [face_begin[f], face_begin[f+1]) of `corners`) into a RawMesh.
absl::StatusOr<RawMesh> FanTriangulateRaw(std::vector<Vec3> positions,
                                          const std::vector<int32_t>& corners,
                                          const std::vector<size_t>& face_begin,
                                          const std::string& name);

}  // namespace geodex::mesh::io_internal
