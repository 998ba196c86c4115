#include "client/cli/outputs.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_replace.h"
#include "absl/strings/strip.h"

namespace geodex::client::cli {
namespace {

std::string JsonNumber(double v) {
  if (std::isfinite(v)) return absl::StrFormat("%.17g", v);
  // JSON has no infinity; null keeps the document valid.
  return "null";
}

std::string JsonArray(const std::array<double, 3>& v) {
  return absl::StrCat("[", JsonNumber(v[0]), ", ", JsonNumber(v[1]), ", ", JsonNumber(v[2]), "]");
}

}  // namespace

std::string PathsToObj(const std::vector<GeodesicPath>& paths) {
  std::string out = absl::StrFormat("# geodex geodesic paths: %d\n", paths.size());
  for (const GeodesicPath& path : paths) {
    for (const Position& p : path.positions) {
      absl::StrAppendFormat(&out, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
    }
  }
  size_t next = 1;  // OBJ indices are 1-based
  for (size_t i = 0; i < paths.size(); ++i) {
    const size_t n = paths[i].positions.size();
    absl::StrAppendFormat(&out, "# path %d length %.17g\n", i, paths[i].length);
    if (n == 1) absl::StrAppendFormat(&out, "p %d\n", next);
    if (n >= 2) {
      out += "l";
      for (size_t k = 0; k < n; ++k) absl::StrAppendFormat(&out, " %d", next + k);
      out += "\n";
    }
    next += n;
  }
  return out;
}

std::string PathsToPly(const std::vector<GeodesicPath>& paths) {
  size_t vertices = 0, edges = 0;
  for (const GeodesicPath& path : paths) {
    vertices += path.positions.size();
    if (!path.positions.empty()) edges += path.positions.size() - 1;
  }
  std::string out = absl::StrFormat(
      "ply\nformat ascii 1.0\ncomment geodex geodesic paths: %d\n"
      "element vertex %d\nproperty double x\nproperty double y\nproperty double z\n"
      "property int path\n"
      "element edge %d\nproperty int vertex1\nproperty int vertex2\nend_header\n",
      paths.size(), vertices, edges);
  for (size_t i = 0; i < paths.size(); ++i) {
    for (const Position& p : paths[i].positions) {
      absl::StrAppendFormat(&out, "%.17g %.17g %.17g %d\n", p[0], p[1], p[2], i);
    }
  }
  size_t first = 0;
  for (const GeodesicPath& path : paths) {
    for (size_t k = 1; k < path.positions.size(); ++k) {
      absl::StrAppendFormat(&out, "%d %d\n", first + k - 1, first + k);
    }
    first += path.positions.size();
  }
  return out;
}

std::string PathsToJson(const std::vector<GeodesicPath>& paths) {
  std::string out = "[\n";
  for (size_t i = 0; i < paths.size(); ++i) {
    const GeodesicPath& path = paths[i];
    absl::StrAppend(&out, "  {\"length\": ", JsonNumber(path.length), ", \"points\": [");
    for (size_t k = 0; k < path.points.size(); ++k) {
      const SurfacePoint& p = path.points[k];
      absl::StrAppend(&out, k ? ", " : "", "{\"face\": ", p.face, ", \"w\": ", JsonArray(p.w),
                      ", \"xyz\": ", JsonArray(path.positions[k]), "}");
    }
    absl::StrAppend(&out, "]}", i + 1 < paths.size() ? ",\n" : "\n");
  }
  out += "]\n";
  return out;
}

std::string FieldToText(const VertexDistances& field) {
  std::string out;
  out.reserve(field.distances.size() * 20);
  const bool nearest = !field.nearest_source.empty();
  char buffer[64];
  for (size_t v = 0; v < field.distances.size(); ++v) {
    const double d = field.distances[v];
    if (std::isinf(d)) {
      out += "inf";
    } else {
      const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), d);
      out.append(buffer, ptr);
    }
    if (nearest) absl::StrAppend(&out, " ", field.nearest_source[v]);
    out += '\n';
  }
  return out;
}

std::string FieldWithinToText(const VertexDistancesWithin& field) {
  std::string out;
  out.reserve(field.distances.size() * 28);
  const bool nearest = !field.nearest_source.empty();
  char buffer[64];
  for (size_t i = 0; i < field.vertices.size(); ++i) {
    absl::StrAppend(&out, field.vertices[i], " ");
    const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), field.distances[i]);
    out.append(buffer, ptr);
    if (nearest) absl::StrAppend(&out, " ", field.nearest_source[i]);
    out += '\n';
  }
  return out;
}

std::vector<double> DenseDistances(const VertexDistancesWithin& field, size_t num_vertices) {
  std::vector<double> dense(num_vertices, std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < field.vertices.size(); ++i) {
    const int32_t v = field.vertices[i];
    if (v >= 0 && static_cast<size_t>(v) < num_vertices) dense[v] = field.distances[i];
  }
  return dense;
}

std::array<uint8_t, 3> RampColor(double t) {
  // A few stops of a perceptually ordered dark-blue -> teal -> yellow ramp
  // (close to matplotlib's viridis), linearly interpolated.
  static constexpr double kStops[][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  constexpr int kLast = 4;
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0);
  const double x = t * kLast;
  const int i = std::min(kLast - 1, static_cast<int>(x));
  const double f = x - i;
  std::array<uint8_t, 3> rgb;
  for (int c = 0; c < 3; ++c) {
    rgb[c] =
        static_cast<uint8_t>(std::lround(kStops[i][c] + f * (kStops[i + 1][c] - kStops[i][c])));
  }
  return rgb;
}

std::string FieldToPly(const Mesh& mesh, const std::vector<double>& distances) {
  double max_distance = 0;
  for (double d : distances) {
    if (std::isfinite(d)) max_distance = std::max(max_distance, d);
  }
  std::string out = absl::StrFormat(
      "ply\nformat ascii 1.0\ncomment geodex distance field (quality = geodesic distance)\n"
      "element vertex %d\nproperty double x\nproperty double y\nproperty double z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float quality\n"
      "element face %d\nproperty list uchar int vertex_indices\nend_header\n",
      mesh.positions.size(), mesh.faces.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const Position& p = mesh.positions[v];
    const double d = distances[v];
    std::array<uint8_t, 3> rgb = kUnreachableColor;
    if (std::isfinite(d)) rgb = RampColor(max_distance > 0 ? d / max_distance : 0.0);
    // PLY has no infinity for float; -1 marks "unreachable" in the quality.
    absl::StrAppendFormat(&out, "%.17g %.17g %.17g %d %d %d %.9g\n", p[0], p[1], p[2], rgb[0],
                          rgb[1], rgb[2], std::isfinite(d) ? d : -1.0);
  }
  for (const auto& f : mesh.faces) absl::StrAppendFormat(&out, "3 %d %d %d\n", f[0], f[1], f[2]);
  return out;
}

std::string ModelsTable(const std::vector<ModelInfo>& models) {
  std::string out = absl::StrFormat("%-24s %8s %-10s %10s %10s %8s\n", "MODEL", "VERSION", "STATE",
                                    "VERTICES", "FACES", "SAMPLES");
  for (const ModelInfo& m : models) {
    absl::StrAppendFormat(&out, "%-24s %8d %-10s %10d %10d %8d%s\n", m.name, m.version,
                          StateName(m.state), m.num_vertices, m.num_faces, m.num_samples,
                          m.reason.empty() ? "" : "  " + m.reason);
  }
  return out;
}

std::string ModelToJson(const ModelInfo& m) {
  std::vector<std::string> report;
  for (const auto& [key, value] : m.build_report) {
    report.push_back(absl::StrCat("    ", JsonString(key), ": ", JsonString(value)));
  }
  return absl::StrCat(
      "{\n  \"name\": ", JsonString(m.name), ",\n  \"version\": ", m.version,
      ",\n  \"available_versions\": [", absl::StrJoin(m.available_versions, ", "),
      "],\n  \"state\": ", JsonString(StateName(m.state)),
      ",\n  \"reason\": ", JsonString(m.reason), ",\n  \"num_vertices\": ", m.num_vertices,
      ",\n  \"num_faces\": ", m.num_faces, ",\n  \"num_samples\": ", m.num_samples,
      ",\n  \"num_triangles\": ", m.num_triangles, ",\n  \"bbox_min\": ", JsonArray(m.bbox_min),
      ",\n  \"bbox_max\": ", JsonArray(m.bbox_max),
      ",\n  \"requested_samples\": ", m.requested_samples, ",\n  \"seed\": ", m.seed,
      ",\n  \"samples_added_by_repair\": ", m.samples_added_by_repair,
      ",\n  \"builder_version\": ", JsonString(m.builder_version),
      ",\n  \"mapped_bytes\": ", m.mapped_bytes, ",\n  \"mesh_hash\": ", m.mesh_hash,
      ",\n  \"build_report\": {", report.empty() ? "" : "\n", absl::StrJoin(report, ",\n"),
      report.empty() ? "}" : "\n  }",
      // The server's report JSON, verbatim but for its indentation.
      m.report_json.empty()
          ? ""
          : absl::StrCat(",\n  \"report\": ",
                         absl::StrReplaceAll(absl::StripTrailingAsciiWhitespace(m.report_json),
                                             {{"\n", "\n  "}})),
      "\n}\n");
}

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          absl::StrAppendFormat(&out, "\\u%04x", static_cast<int>(c));
        } else {
          out += c;
        }
    }
  }
  out += "\"";
  return out;
}

}  // namespace geodex::client::cli
