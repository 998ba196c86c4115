#include "core/mesh/pairs_io.h"

#include <charconv>
#include <cmath>
#include <iostream>
#include <iterator>

#include "absl/strings/str_format.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"

namespace geodex::mesh {
namespace {

// Splits on spaces, tabs and commas, dropping empty fields.
std::vector<std::string_view> Fields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() &&
           (line[i] == ' ' || line[i] == '\t' || line[i] == ',' || line[i] == '\r')) {
      ++i;
    }
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != ',' &&
           line[i] != '\r') {
      ++i;
    }
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

// The fields of each line of `contents` that is neither blank nor a '#'
// comment, with its 1-based line number, to `fn`, which returns a Status;
// the first error ends the walk.
template <typename Fn>
absl::Status ForEachLine(std::string_view contents, Fn fn) {
  int64_t line_number = 0;
  size_t begin = 0;
  while (begin < contents.size()) {
    size_t end = contents.find('\n', begin);
    if (end == std::string_view::npos) end = contents.size();
    const std::string_view line = contents.substr(begin, end - begin);
    begin = end + 1;
    ++line_number;
    const std::vector<std::string_view> fields = Fields(line);
    if (fields.empty() || fields[0][0] == '#') continue;
    GEODEX_RETURN_IF_ERROR(fn(line_number, fields));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::vector<PointPair>> ParsePairs(std::string_view contents) {
  std::vector<PointPair> pairs;
  GEODEX_RETURN_IF_ERROR(ForEachLine(contents, [&](int64_t line_number,
                                                   const std::vector<std::string_view>& fields) {
    if (fields.size() != 8) {
      return absl::InvalidArgumentError(
          absl::StrFormat("line %d: expected 8 fields 'fa a0 a1 a2 fb b0 b1 b2', found %d",
                          line_number, fields.size()));
    }
    PointPair pair;
    pair.line = line_number;
    SurfacePoint* points[2] = {&pair.a, &pair.b};
    for (int k = 0; k < 2; ++k) {
      const std::string_view face_text = fields[4 * k];
      int64_t face = 0;
      const auto [ptr, ec] =
          std::from_chars(face_text.data(), face_text.data() + face_text.size(), face);
      if (ec != std::errc() || ptr != face_text.data() + face_text.size() || face < 0 ||
          face > INT32_MAX) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "line %d: field %d ('%s') is not a face id", line_number, 4 * k + 1, face_text));
      }
      points[k]->face = static_cast<int32_t>(face);
      for (int i = 0; i < 3; ++i) {
        const std::string_view text = fields[4 * k + 1 + i];
        double value = 0;
        const auto [p2, ec2] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (ec2 != std::errc() || p2 != text.data() + text.size() || !std::isfinite(value)) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "line %d: field %d ('%s') is not a finite number", line_number, 4 * k + 2 + i, text));
        }
        points[k]->w[i] = value;
      }
    }
    pairs.push_back(pair);
    return absl::OkStatus();
  }));
  return pairs;
}

absl::StatusOr<std::vector<NumberLine>> ParseNumberLines(std::string_view contents,
                                                         size_t width) {
  std::vector<NumberLine> lines;
  GEODEX_RETURN_IF_ERROR(ForEachLine(contents, [&](int64_t line_number,
                                                   const std::vector<std::string_view>& fields) {
    NumberLine out;
    out.line = line_number;
    for (const std::string_view text : fields) {
      double value = 0;
      const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (ec != std::errc() || ptr != text.data() + text.size()) break;
      out.values.push_back(value);
    }
    if (out.values.size() != fields.size() || fields.size() != width) {
      return absl::InvalidArgumentError(
          absl::StrFormat("line %d: expected %d numbers", line_number, width));
    }
    for (const double v : out.values) {
      if (!std::isfinite(v)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("line %d: non-finite number", line_number));
      }
    }
    lines.push_back(std::move(out));
    return absl::OkStatus();
  }));
  return lines;
}

absl::Status ValidatePairs(const Mesh& mesh, const std::vector<PointPair>& pairs) {
  for (const PointPair& pair : pairs) {
    for (const SurfacePoint* p : {&pair.a, &pair.b}) {
      const absl::Status status = ValidateSurfacePoint(mesh, *p);
      if (!status.ok()) {
        return absl::Status(status.code(),
                            absl::StrFormat("line %d: %s", pair.line, status.message()));
      }
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<std::string> ReadFileOrStdin(const std::string& path) {
  if (path == "-") {
    return std::string(std::istreambuf_iterator<char>(std::cin), {});
  }
  return ReadWholeFile(path);
}

std::string FormatDistance(double d) {
  if (std::isinf(d)) return "inf";
  char buffer[64];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), d);
  return std::string(buffer, ptr);
}

}  // namespace geodex::mesh
