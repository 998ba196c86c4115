// geodex-query: answers queries offline from an index file, without a server.
//
//   geodex-query INDEX --pairs FILE [--near-pairs path|unfold|exact] [--error-bounds]
//                [--tolerance X] [--linear-baseline]
//   geodex-query INDEX --paths FILE [--format xyz|json] [--exact-path-corridor K]
//   geodex-query INDEX --field SOURCES [--nearest]
//   geodex-query INDEX --locate POINTS
//   geodex-query INDEX --expmap "F W0 W1 W2" --radius R [--direction X Y Z]
//   geodex-query INDEX --info
//
// FILE holds lines "fa a0 a1 a2 fb b0 b1 b2" (core/mesh/pairs_io.h); SOURCES
// lines "f w0 w1 w2"; POINTS lines "x y z". "-" reads standard input.
// --expmap prints "vertex u v" for every vertex within R of the centre (the
// exponential map, core/query/exp_map.h), ascending by vertex id. Face and
// vertex ids, in and out, are those of the mesh file the index was built
// from, also when the builder repaired it (core/query/input_ids.h). Output
// goes to standard output in input order; on a bad line nothing is printed and
// the error names the line. Exit codes: 0 ok, 2 bad input, 1 other errors.

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "CLI/CLI.hpp"
#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/mesh/pairs_io.h"
#include "core/query/exp_map.h"
#include "core/query/input_ids.h"
#include "core/query/query_engine.h"

namespace geodex {
namespace {

// The whitespace-separated numbers of `text`; nullopt when something else
// follows them.
std::optional<std::vector<double>> ParseNumbers(const std::string& text) {
  std::vector<double> values;
  const char* p = text.c_str();
  char* next = nullptr;
  while (true) {
    const double v = std::strtod(p, &next);
    if (next == p) break;
    values.push_back(v);
    p = next;
  }
  while (*p == ' ' || *p == '\t' || *p == '\r') ++p;
  if (*p != '\0') return std::nullopt;
  return values;
}

// Lines of `width` numbers; errors name the line.
absl::StatusOr<std::vector<std::vector<double>>> ReadNumberLines(const std::string& path,
                                                                 size_t width) {
  GEODEX_ASSIGN_OR_RETURN(const std::string text, mesh::ReadFileOrStdin(path));
  std::vector<std::vector<double>> lines;
  size_t begin = 0;
  int64_t number = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(begin, end - begin);
    begin = end + 1;
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos ||
        line[line.find_first_not_of(" \t")] == '#') {
      continue;
    }
    const std::optional<std::vector<double>> values = ParseNumbers(line);
    if (!values || values->size() != width) {
      return absl::InvalidArgumentError(
          absl::StrFormat("line %d: expected %d numbers", number, width));
    }
    for (double v : *values) {
      if (!std::isfinite(v)) {
        return absl::InvalidArgumentError(absl::StrFormat("line %d: non-finite number", number));
      }
    }
    lines.push_back(*values);
  }
  return lines;
}

// Validates the points (in input ids) and turns them into the index's ids.
absl::Status CheckPairs(const query::QueryEngine& engine, std::vector<mesh::PointPair>& pairs) {
  for (mesh::PointPair& pair : pairs) {
    for (mesh::SurfacePoint* p : {&pair.a, &pair.b}) {
      absl::StatusOr<mesh::SurfacePoint> internal =
          engine.input_ids().ToInternal(*p, engine.options().weight_tolerance);
      if (!internal.ok()) {
        return absl::Status(internal.status().code(),
                            absl::StrFormat("line %d: %s", pair.line, internal.status().message()));
      }
      *p = *internal;
    }
  }
  return absl::OkStatus();
}

// "F W0 W1 W2" as a surface point.
absl::StatusOr<mesh::SurfacePoint> ParseCentre(const std::string& text) {
  const std::vector<double> values = ParseNumbers(text).value_or(std::vector<double>{});
  if (values.size() != 4 || values[0] != std::floor(values[0]) ||
      !(std::abs(values[0]) < 2147483648.0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "--expmap wants \"F W0 W1 W2\" (a face id and three weights), got \"%s\"", text));
  }
  return mesh::SurfacePoint{static_cast<int32_t>(values[0]), {values[1], values[2], values[3]}};
}

struct Args {
  std::string expmap;
  double radius = 0;
  std::vector<double> direction;
  std::string index, pairs, paths, field, locate, format = "xyz", near_pairs = "path";
  bool exact_near = false, baseline = false, nearest = false, error_bounds = false, info = false;
  double tolerance = 0;
  int32_t exact_path_corridor = 0;
};

absl::Status Run(const Args& args) {
  GEODEX_ASSIGN_OR_RETURN(auto index, index::Index::Open(args.index));
  if (args.info) {
    // The header's counts, then the builder's report (with the accuracy
    // calibration's figures when the index has one).
    // Vertices and faces count the mesh file's; the counts of the mesh the
    // index answers on (repaired, refined) follow.
    const index::FileHeader& h = index->header();
    const query::InputIds ids(*index);
    std::string out = absl::StrFormat(
        "format = %d.%d\nbuilder = %s\nvertices = %d\nfaces = %d\nsamples = %d\n"
        "requested_samples = %d\ntriangles = %d\nbytes = %d\nerror_bounds = %s\n",
        h.format_major, h.format_minor, index->builder_version(), ids.num_input_vertices(),
        ids.num_input_faces(), index->num_samples(), h.params.requested_samples,
        index->num_triangles(), index->size_bytes(),
        index->accuracy() != nullptr ? "yes" : "no (geodex-build calibrate adds them)");
    if (!ids.identity()) {
      out += absl::StrFormat("internal_vertices = %d\ninternal_faces = %d\n", index->num_vertices(),
                             index->num_faces());
    }
    out += index->report();
    std::fwrite(out.data(), 1, out.size(), stdout);
    return absl::OkStatus();
  }
  query::QueryOptions options;
  query::DistanceOptions distance_options;
  distance_options.near_pairs = args.exact_near || args.near_pairs == "exact"
                                    ? query::NearPairs::kExact
                                : args.near_pairs == "unfold" ? query::NearPairs::kUnfold
                                                              : query::NearPairs::kPath;
  distance_options.tolerance = args.tolerance;
  options.exact_path_corridor = args.exact_path_corridor;
  GEODEX_ASSIGN_OR_RETURN(auto engine, query::QueryEngine::Create(index, options));
  std::string out;
  if (!args.pairs.empty() || !args.paths.empty()) {
    const bool paths = args.pairs.empty();
    GEODEX_ASSIGN_OR_RETURN(const std::string text,
                            mesh::ReadFileOrStdin(paths ? args.paths : args.pairs));
    GEODEX_ASSIGN_OR_RETURN(auto pairs, mesh::ParsePairs(text));
    GEODEX_RETURN_IF_ERROR(CheckPairs(*engine, pairs));
    query::QueryScratch scratch;
    if (paths && args.format == "json") out += "[\n";
    for (size_t i = 0; i < pairs.size(); ++i) {
      const mesh::PointPair& pair = pairs[i];
      if (!paths) {
        double d, bound = 0;
        if (args.baseline) {
          d = engine->LinearInterpolationDistance(pair.a, pair.b);
        } else {
          auto answer = engine->Distance(pair.a, pair.b, distance_options, &scratch,
                                         args.error_bounds ? &bound : nullptr);
          if (!answer.ok()) {
            return absl::Status(answer.status().code(), absl::StrFormat("line %d: %s", pair.line,
                                                                        answer.status().message()));
          }
          d = *answer;
        }
        out += mesh::FormatDistance(d);
        if (args.error_bounds) out += " " + mesh::FormatDistance(bound);
        out += "\n";
        continue;
      }
      auto path = engine->Path(pair.a, pair.b);
      if (!path.ok()) {
        return absl::Status(path.status().code(),
                            absl::StrFormat("line %d: %s", pair.line, path.status().message()));
      }
      engine->input_ids().PathToInput(*path);
      if (args.format == "json") {
        out += "  [";
        for (size_t k = 0; k < path->size(); ++k) {
          const auto& p = (*path)[k];
          out += absl::StrFormat(
              "%s{\"face\": %d, \"w\": [%.17g, %.17g, %.17g], \"xyz\": [%.17g, %.17g, %.17g]}",
              k ? ", " : "", p.point.face, p.point.w[0], p.point.w[1], p.point.w[2], p.position.x(),
              p.position.y(), p.position.z());
        }
        out += i + 1 < pairs.size() ? "],\n" : "]\n";
      } else {
        for (const auto& p : *path) {
          out += absl::StrFormat("%.17g %.17g %.17g\n", p.position.x(), p.position.y(),
                                 p.position.z());
        }
        out += "\n";
      }
    }
    if (paths && args.format == "json") out += "]\n";
  } else if (!args.field.empty()) {
    GEODEX_ASSIGN_OR_RETURN(const auto lines, ReadNumberLines(args.field, 4));
    std::vector<mesh::SurfacePoint> sources;
    for (const auto& l : lines) {
      GEODEX_ASSIGN_OR_RETURN(
          const mesh::SurfacePoint p,
          engine->input_ids().ToInternal({static_cast<int32_t>(l[0]), {l[1], l[2], l[3]}},
                                         engine->options().weight_tolerance));
      sources.push_back(p);
    }
    GEODEX_ASSIGN_OR_RETURN(auto field, engine->Field(sources));
    field = engine->input_ids().FieldToInput(std::move(field));
    for (size_t v = 0; v < field.distance.size(); ++v) {
      out += mesh::FormatDistance(field.distance[v]);
      if (args.nearest) out += absl::StrFormat(" %d", field.nearest[v]);
      out += "\n";
    }
  } else if (!args.locate.empty()) {
    GEODEX_ASSIGN_OR_RETURN(const auto lines, ReadNumberLines(args.locate, 3));
    for (const auto& l : lines) {
      GEODEX_ASSIGN_OR_RETURN(auto located, engine->Locate({l[0], l[1], l[2]}));
      located.point = engine->input_ids().ToInput(located.point);
      out += absl::StrFormat("%d %.17g %.17g %.17g %.17g\n", located.point.face, located.point.w[0],
                             located.point.w[1], located.point.w[2], located.distance);
    }
  } else if (!args.expmap.empty()) {
    GEODEX_ASSIGN_OR_RETURN(const mesh::SurfacePoint centre, ParseCentre(args.expmap));
    query::ExpMapOptions map_options;
    map_options.radius = args.radius;
    map_options.distance = distance_options;
    if (!args.direction.empty()) {
      map_options.reference_direction =
          mesh::Vec3(args.direction[0], args.direction[1], args.direction[2]);
    }
    query::QueryScratch scratch;
    GEODEX_ASSIGN_OR_RETURN(const auto map,
                            query::ExpMapOfInput(*engine, centre, map_options, &scratch));
    for (const query::ExpMapVertex& e : map) {
      out += absl::StrFormat("%d %.17g %.17g\n", e.vertex, e.u, e.v);
    }
  } else {
    return absl::InvalidArgumentError("give one of --pairs, --paths, --field, --locate, --expmap");
  }
  std::fwrite(out.data(), 1, out.size(), stdout);
  return absl::OkStatus();
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  geodex::Args args;
  CLI::App app{"geodex-query: geodesic queries from an index file, offline."};
  app.add_option("index", args.index, "Index file (.gdx)")->required();
  auto* pairs =
      app.add_option("--pairs", args.pairs, "Distances for lines 'fa a0 a1 a2 fb b0 b1 b2'");
  auto* paths = app.add_option("--paths", args.paths, "Paths for lines 'fa a0 a1 a2 fb b0 b1 b2'");
  auto* field = app.add_option("--field", args.field, "Distance field from lines 'f w0 w1 w2'");
  auto* locate = app.add_option("--locate", args.locate, "Closest surface points to lines 'x y z'");
  auto* expmap = app.add_option("--expmap", args.expmap,
                                "Exponential map round the point \"F W0 W1 W2\": 'vertex u v' "
                                "for every vertex within --radius");
  app.add_option("--radius", args.radius, "With --expmap: the geodesic radius")->needs(expmap);
  app.add_option("--direction", args.direction,
                 "With --expmap: the reference direction X Y Z (theta = 0), projected into "
                 "the centre's face; default its first edge")
      ->expected(3)
      ->needs(expmap);
  auto* info = app.add_flag("--info", args.info,
                            "The index's counts and build report, with its accuracy figures");
  pairs->excludes(paths)->excludes(field)->excludes(locate)->excludes(info)->excludes(expmap);
  paths->excludes(field)->excludes(locate)->excludes(expmap);
  field->excludes(locate)->excludes(expmap);
  locate->excludes(expmap);
  app.add_option("--near-pairs", args.near_pairs,
                 "Near pairs (the same or adjacent geodesic triangles, or closer than 3 scale "
                 "lengths): path (the traced path's length, default), unfold (pure O(1)) or "
                 "exact (local exact propagation)")
      ->check(CLI::IsMember({"path", "unfold", "exact"}));
  app.add_flag("--exact-near-pairs", args.exact_near, "Same as --near-pairs exact");
  app.add_flag("--error-bounds", args.error_bounds,
               "With --pairs: print 'distance bound' per line, bound = the answer's absolute "
               "error bound (needs an index with its accuracy calibration)");
  app.add_option("--tolerance", args.tolerance,
                 "With --pairs: relative error tolerance (e.g. 0.005): refine every pair whose "
                 "bound exceeds tolerance x distance (0: off)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--exact-path-corridor", args.exact_path_corridor,
                 "With --paths: also solve exactly within this many edge steps of the traced "
                 "path and keep the shorter (not O(k); 0: off)")
      ->check(CLI::Range(0, 64));
  app.add_flag("--linear-baseline", args.baseline, "The paper's linear interpolation (§6.3)");
  app.add_flag("--nearest", args.nearest, "With --field: also print the nearest source");
  app.add_option("--format", args.format, "Path output: xyz (blank line between paths) or json")
      ->check(CLI::IsMember({"xyz", "json"}));
  CLI11_PARSE(app, argc, argv);
  const absl::Status status = geodex::Run(args);
  if (!status.ok()) {
    std::fprintf(stderr, "geodex-query: %s\n", status.ToString().c_str());
    return status.code() == absl::StatusCode::kInvalidArgument ||
                   status.code() == absl::StatusCode::kOutOfRange ||
                   status.code() == absl::StatusCode::kNotFound
               ? 2
               : 1;
  }
  return 0;
}
