#include "core/mesh/pairs_io.h"

#include <charconv>
#include <cmath>
#include <iostream>
#include <iterator>
#include <optional>

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

namespace {

// The integer of `text` in [0, INT32_MAX], or nullopt.
std::optional<int32_t> Id(std::string_view text) {
  int64_t id = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), id);
  if (ec != std::errc() || ptr != text.data() + text.size() || id < 0 || id > INT32_MAX) {
    return std::nullopt;
  }
  return static_cast<int32_t>(id);
}

// Point k of `pair` from fields[first...]: "v ID" (the vertex id kept for
// ResolveVertices) or "f w0 w1 w2".
absl::Status ParsePoint(const std::vector<std::string_view>& fields, size_t first, int k,
                        int64_t line_number, PointPair* pair) {
  SurfacePoint& p = k == 0 ? pair->a : pair->b;
  if (fields[first] == "v") {
    const std::optional<int32_t> vertex = Id(fields[first + 1]);
    if (!vertex) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "line %d: field %d ('%s') is not a vertex id", line_number, first + 2,
          fields[first + 1]));
    }
    pair->vertex[k] = *vertex;
    return absl::OkStatus();
  }
  const std::optional<int32_t> face = Id(fields[first]);
  if (!face) {
    return absl::InvalidArgumentError(absl::StrFormat("line %d: field %d ('%s') is not a face id",
                                                      line_number, first + 1, fields[first]));
  }
  p.face = *face;
  for (int i = 0; i < 3; ++i) {
    const std::string_view text = fields[first + 1 + i];
    double value = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "line %d: field %d ('%s') is not a finite number", line_number, first + 2 + i, text));
    }
    p.w[i] = value;
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::vector<PointPair>> ParsePairs(std::string_view contents) {
  std::vector<PointPair> pairs;
  GEODEX_RETURN_IF_ERROR(ForEachLine(contents, [&](int64_t line_number,
                                                   const std::vector<std::string_view>& fields) {
    // A point is "f w0 w1 w2" or "v ID".
    const size_t first_b = !fields.empty() && fields[0] == "v" ? 2 : 4;
    const size_t expected =
        first_b + (fields.size() > first_b && fields[first_b] == "v" ? 2 : 4);
    if (fields.size() != expected) {
      if (expected == 8) {
        return absl::InvalidArgumentError(
            absl::StrFormat("line %d: expected 8 fields 'fa a0 a1 a2 fb b0 b1 b2', found %d",
                            line_number, fields.size()));
      }
      return absl::InvalidArgumentError(absl::StrFormat(
          "line %d: expected %d fields ('fa a0 a1 a2 fb b0 b1 b2', a point 'v ID' for a "
          "vertex), found %d",
          line_number, expected, fields.size()));
    }
    PointPair pair;
    pair.line = line_number;
    GEODEX_RETURN_IF_ERROR(ParsePoint(fields, 0, 0, line_number, &pair));
    GEODEX_RETURN_IF_ERROR(ParsePoint(fields, first_b, 1, line_number, &pair));
    pairs.push_back(pair);
    return absl::OkStatus();
  }));
  return pairs;
}

absl::Status ResolveVertices(const std::function<absl::StatusOr<SurfacePoint>(int32_t)>& vertex_point,
                             std::vector<PointPair>* pairs) {
  for (PointPair& pair : *pairs) {
    for (int k = 0; k < 2; ++k) {
      if (pair.vertex[k] == kNone) continue;
      absl::StatusOr<SurfacePoint> p = vertex_point(pair.vertex[k]);
      if (!p.ok()) {
        return absl::Status(p.status().code(),
                            absl::StrFormat("line %d: %s", pair.line, p.status().message()));
      }
      (k == 0 ? pair.a : pair.b) = *p;
    }
  }
  return absl::OkStatus();
}

std::vector<SurfacePoint> LowestFacePoints(const Mesh& mesh) {
  std::vector<SurfacePoint> points(mesh.num_vertices(), SurfacePoint{kNone, {0, 0, 0}});
  for (int32_t f = 0; f < mesh.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      SurfacePoint& p = points[mesh.face(f)[k]];
      if (p.face != kNone) continue;
      p.face = f;
      p.w[k] = 1;
    }
  }
  return points;
}

absl::StatusOr<SurfacePoint> VertexPointOf(std::span<const SurfacePoint> lowest_face_points,
                                           int32_t v) {
  if (v < 0 || v >= static_cast<int64_t>(lowest_face_points.size())) {
    return absl::OutOfRangeError(
        absl::StrFormat("vertex id %d out of range [0, %d)", v, lowest_face_points.size()));
  }
  if (lowest_face_points[v].face == kNone) {
    return absl::InvalidArgumentError(absl::StrFormat("vertex %d lies on no face of the mesh", v));
  }
  return lowest_face_points[v];
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
