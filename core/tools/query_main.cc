// geodex-query: answers queries offline from an index file, without a server.
//
//   geodex-query INDEX --pairs FILE [--near-pairs path|unfold|exact] [--error-bounds]
//                [--tolerance X] [--linear-baseline]
//   geodex-query INDEX --paths FILE [--format xyz|json] [--exact-path-corridor K]
//   geodex-query INDEX --field SOURCES [--nearest]
//   geodex-query INDEX --locate POINTS
//   geodex-query INDEX --expmap "F W0 W1 W2" --radius R [--direction X Y Z]
//   geodex-query INDEX --info [--format text|json]
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
#include "core/index/index_report.h"
#include "core/mesh/pairs_io.h"
#include "core/query/input_queries.h"

namespace geodex {
namespace {

struct Args {
  std::string expmap;
  double radius = 0;
  std::vector<double> direction;
  std::string index, pairs, paths, field, locate, format = "xyz", near_pairs = "path";
  bool exact_near = false, baseline = false, nearest = false, error_bounds = false, info = false;
  double tolerance = 0;
  int32_t exact_path_corridor = 0;
};

// The pairs of `path`, read into `a` and `b`; errors name the line.
absl::StatusOr<std::vector<mesh::PointPair>> ReadPairs(const query::InputQueries& queries,
                                                       const std::string& path,
                                                       query::EnginePoints* a,
                                                       query::EnginePoints* b) {
  GEODEX_ASSIGN_OR_RETURN(const std::string text, mesh::ReadFileOrStdin(path));
  GEODEX_ASSIGN_OR_RETURN(std::vector<mesh::PointPair> pairs, mesh::ParsePairs(text));
  // Both points of a line are checked before the next line's, as the
  // errors name lines.
  std::vector<mesh::SurfacePoint> both, pa, pb;
  for (const mesh::PointPair& pair : pairs) {
    both.insert(both.end(), {pair.a, pair.b});
    pa.push_back(pair.a);
    pb.push_back(pair.b);
  }
  GEODEX_RETURN_IF_ERROR(queries.Read(
      both, [&](size_t i) { return absl::StrFormat("line %d", pairs[i / 2].line); }, a));
  GEODEX_RETURN_IF_ERROR(queries.Read(pa, nullptr, a));
  GEODEX_RETURN_IF_ERROR(queries.Read(pb, nullptr, b));
  return pairs;
}

// Prefixes a status with the line of the pair it is about.
absl::Status AtLine(const absl::Status& status, int64_t line) {
  return absl::Status(status.code(), absl::StrFormat("line %d: %s", line, status.message()));
}

absl::StatusOr<std::string> Distances(const query::InputQueries& queries, const Args& args,
                                      const query::DistanceOptions& options) {
  query::EnginePoints a, b;
  GEODEX_ASSIGN_OR_RETURN(const auto pairs, ReadPairs(queries, args.pairs, &a, &b));
  query::QueryScratch scratch;
  std::string out;
  for (size_t i = 0; i < pairs.size(); ++i) {
    double d, bound = 0;
    if (args.baseline) {
      d = queries.LinearInterpolationDistance(a, i, b, i);
    } else {
      absl::StatusOr<double> answer =
          queries.Distance(a, i, b, i, options, &scratch, args.error_bounds ? &bound : nullptr);
      if (!answer.ok()) return AtLine(answer.status(), pairs[i].line);
      d = *answer;
    }
    out += mesh::FormatDistance(d);
    if (args.error_bounds) out += " " + mesh::FormatDistance(bound);
    out += "\n";
  }
  return out;
}

absl::StatusOr<std::string> Paths(const query::InputQueries& queries, const Args& args) {
  query::EnginePoints a, b;
  GEODEX_ASSIGN_OR_RETURN(const auto pairs, ReadPairs(queries, args.paths, &a, &b));
  const bool json = args.format == "json";
  std::string out = json ? "[\n" : "";
  for (size_t i = 0; i < pairs.size(); ++i) {
    absl::StatusOr<std::vector<query::PathPoint>> path =
        queries.Path(a, i, b, i, args.exact_path_corridor);
    if (!path.ok()) return AtLine(path.status(), pairs[i].line);
    if (json) {
      out += "  [";
      for (size_t k = 0; k < path->size(); ++k) {
        const query::PathPoint& p = (*path)[k];
        out += absl::StrFormat(
            "%s{\"face\": %d, \"w\": [%.17g, %.17g, %.17g], \"xyz\": [%.17g, %.17g, %.17g]}",
            k ? ", " : "", p.point.face, p.point.w[0], p.point.w[1], p.point.w[2], p.position.x(),
            p.position.y(), p.position.z());
      }
      out += i + 1 < pairs.size() ? "],\n" : "]\n";
      continue;
    }
    for (const query::PathPoint& p : *path) {
      out += absl::StrFormat("%.17g %.17g %.17g\n", p.position.x(), p.position.y(),
                             p.position.z());
    }
    out += "\n";
  }
  return json ? out + "]\n" : out;
}

absl::StatusOr<std::string> Field(const query::InputQueries& queries, const Args& args) {
  GEODEX_ASSIGN_OR_RETURN(const std::string text, mesh::ReadFileOrStdin(args.field));
  GEODEX_ASSIGN_OR_RETURN(const auto lines, mesh::ParseNumberLines(text, 4));
  std::vector<mesh::SurfacePoint> points;
  for (const mesh::NumberLine& l : lines) {
    const std::vector<double>& v = l.values;
    points.push_back({static_cast<int32_t>(v[0]), {v[1], v[2], v[3]}});
  }
  query::EnginePoints sources;
  GEODEX_RETURN_IF_ERROR(queries.Read(points, nullptr, &sources));
  GEODEX_ASSIGN_OR_RETURN(const query::DistanceField field, queries.Field(sources));
  std::string out;
  for (size_t v = 0; v < field.distance.size(); ++v) {
    out += mesh::FormatDistance(field.distance[v]);
    if (args.nearest) out += absl::StrFormat(" %d", field.nearest[v]);
    out += "\n";
  }
  return out;
}

absl::StatusOr<std::string> Locate(const query::InputQueries& queries, const Args& args) {
  GEODEX_ASSIGN_OR_RETURN(const std::string text, mesh::ReadFileOrStdin(args.locate));
  GEODEX_ASSIGN_OR_RETURN(const auto lines, mesh::ParseNumberLines(text, 3));
  std::string out;
  for (const mesh::NumberLine& l : lines) {
    GEODEX_ASSIGN_OR_RETURN(const query::LocatedPoint located,
                            queries.Locate({l.values[0], l.values[1], l.values[2]}));
    out += absl::StrFormat("%d %.17g %.17g %.17g %.17g\n", located.point.face, located.point.w[0],
                           located.point.w[1], located.point.w[2], located.distance);
  }
  return out;
}

absl::StatusOr<std::string> ExpMap(const query::InputQueries& queries, const Args& args,
                                   const query::DistanceOptions& options) {
  const absl::StatusOr<std::vector<mesh::NumberLine>> centre =
      mesh::ParseNumberLines(args.expmap, 4);
  if (!centre.ok() || centre->size() != 1 ||
      (*centre)[0].values[0] != std::floor((*centre)[0].values[0]) ||
      !(std::abs((*centre)[0].values[0]) < 2147483648.0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "--expmap wants \"F W0 W1 W2\" (a face id and three weights), got \"%s\"", args.expmap));
  }
  const std::vector<double>& c = (*centre)[0].values;
  query::ExpMapOptions map_options;
  map_options.radius = args.radius;
  map_options.distance = options;
  if (!args.direction.empty()) {
    map_options.reference_direction =
        mesh::Vec3(args.direction[0], args.direction[1], args.direction[2]);
  }
  query::QueryScratch scratch;
  GEODEX_ASSIGN_OR_RETURN(
      const auto map,
      queries.ExpMap({static_cast<int32_t>(c[0]), {c[1], c[2], c[3]}}, map_options, &scratch));
  std::string out;
  for (const query::ExpMapVertex& e : map) {
    out += absl::StrFormat("%d %.17g %.17g\n", e.vertex, e.u, e.v);
  }
  return out;
}

absl::Status Run(const Args& args) {
  query::QueryOptions options;
  options.exact_path_corridor = args.exact_path_corridor;
  GEODEX_ASSIGN_OR_RETURN(const auto queries, query::InputQueries::Open(args.index, options));
  query::DistanceOptions distance_options;
  distance_options.near_pairs = args.exact_near || args.near_pairs == "exact"
                                    ? query::NearPairs::kExact
                                : args.near_pairs == "unfold" ? query::NearPairs::kUnfold
                                                              : query::NearPairs::kPath;
  distance_options.tolerance = args.tolerance;
  absl::StatusOr<std::string> out;
  if (args.info) {
    // The build report (core/index/index_report.h).
    const index::IndexReport report = index::MakeIndexReport(queries->index());
    out = args.format == "json" ? index::IndexReportJson(report)
                                : index::IndexReportText(report, args.index);
  } else if (!args.pairs.empty()) {
    out = Distances(*queries, args, distance_options);
  } else if (!args.paths.empty()) {
    out = Paths(*queries, args);
  } else if (!args.field.empty()) {
    out = Field(*queries, args);
  } else if (!args.locate.empty()) {
    out = Locate(*queries, args);
  } else if (!args.expmap.empty()) {
    out = ExpMap(*queries, args, distance_options);
  } else {
    return absl::InvalidArgumentError("give one of --pairs, --paths, --field, --locate, --expmap");
  }
  if (!out.ok()) return out.status();
  std::fwrite(out->data(), 1, out->size(), stdout);
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
  auto* info =
      app.add_flag("--info", args.info,
                   "The index's build report: mesh, samples, size, error target and accuracy by "
                   "distance (--format json: one JSON object)");
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
  app.add_option("--format", args.format,
                 "Path output: xyz (blank line between paths) or json; --info: text or json")
      ->check(CLI::IsMember({"xyz", "json", "text"}));
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
