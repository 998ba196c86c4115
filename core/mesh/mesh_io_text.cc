#include "core/mesh/mesh_io_text.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <string>
#include <system_error>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace geodex::mesh::io_internal {

absl::Status LineError(const std::string& name, int64_t line, std::string_view message) {
  return absl::InvalidArgumentError(absl::StrFormat("%s: line %d: %s", name, line, message));
}

std::string_view NextToken(std::string_view& rest) {
  size_t b = 0;
  while (b < rest.size() && IsBlank(rest[b])) ++b;
  size_t e = b;
  while (e < rest.size() && !IsBlank(rest[e])) ++e;
  const std::string_view token = rest.substr(b, e - b);
  rest.remove_prefix(e);
  return token;
}

std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  for (std::string_view t = NextToken(line); !t.empty(); t = NextToken(line)) tokens.push_back(t);
  return tokens;
}

std::string_view StripComment(std::string_view line) {
  const size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

bool IsBlankLine(std::string_view line) {
  return std::all_of(line.begin(), line.end(), [](char c) { return IsBlank(c); });
}

std::string Quote(std::string_view token) {
  std::string out = "'";
  for (size_t i = 0; i < token.size() && i < 40; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      absl::StrAppendFormat(&out, "\\x%02x", c);
    }
  }
  if (token.size() > 40) out += "...";
  return out + "'";
}

bool ParseDouble(std::string_view token, double* value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  if (ptr != end) return false;
  if (ec == std::errc::result_out_of_range) {
    const std::string copy(token);
    *value = std::strtod(copy.c_str(), nullptr);
    return std::isfinite(*value);
  }
  return ec == std::errc();
}

bool ParseInt(std::string_view token, int64_t* value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  return ec == std::errc() && ptr == end;
}

absl::Status ParseCoordinates(std::span<const std::string_view> tokens, const std::string& name,
                              int64_t line, Vec3* p) {
  for (int i = 0; i < 3; ++i) {
    if (!ParseDouble(tokens[i], &(*p)[i])) {
      return LineError(name, line,
                       absl::StrCat("coordinate ", Quote(tokens[i]), " is not a number"));
    }
    if (!std::isfinite((*p)[i])) {
      return LineError(name, line, absl::StrCat("coordinate ", Quote(tokens[i]), " is not finite"));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<RawMesh> FanTriangulateRaw(std::vector<Vec3> positions,
                                          const std::vector<int32_t>& corners,
                                          const std::vector<size_t>& face_begin,
                                          const std::string& name) {
  const size_t num_faces = face_begin.size() - 1;
  RawMesh raw;
  raw.name = name;
  raw.triangles.reserve(corners.size() - 2 * num_faces);
  raw.input_face.reserve(corners.size() - 2 * num_faces);
  for (size_t f = 0; f < num_faces; ++f) {
    const size_t b = face_begin[f], e = face_begin[f + 1];
    for (size_t i = b + 1; i + 1 < e; ++i) {
      raw.triangles.push_back({corners[b], corners[i], corners[i + 1]});
      raw.input_face.push_back(static_cast<int32_t>(f));
    }
  }
  raw.polygons = raw.triangles.size() != num_faces;
  raw.positions = std::move(positions);
  return raw;
}

}  // namespace geodex::mesh::io_internal
