#include "core/tools/query_cli.h"

#include <cmath>
#include <optional>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/index/index_report.h"
#include "core/mesh/pairs_io.h"
#include "core/query/exp_map.h"

namespace geodex::tools {
namespace {

// The pairs of `path`, read into `a` and `b`; errors name the line.
absl::StatusOr<std::vector<mesh::PointPair>> ReadPairs(const query::InputQueries& queries,
                                                       const std::string& path,
                                                       query::EnginePoints* a,
                                                       query::EnginePoints* b) {
  GEODEX_ASSIGN_OR_RETURN(const std::string text, mesh::ReadFileOrStdin(path));
  GEODEX_ASSIGN_OR_RETURN(std::vector<mesh::PointPair> pairs, mesh::ParsePairs(text));
  GEODEX_RETURN_IF_ERROR(mesh::ResolveVertices(
      [&](int32_t v) { return queries.VertexPoint(v); }, &pairs));
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

// One path of PathsText as a JSON object (its length and its points, as
// the geodex command line writes them), without a line end.
std::string PathJson(const std::vector<query::PathPoint>& path) {
  std::string out = absl::StrFormat("  {\"length\": %.17g, \"points\": [", query::PathLength(path));
  for (size_t k = 0; k < path.size(); ++k) {
    const query::PathPoint& p = path[k];
    out += absl::StrFormat(
        "%s{\"face\": %d, \"w\": [%.17g, %.17g, %.17g], \"xyz\": [%.17g, %.17g, %.17g]}",
        k ? ", " : "", p.point.face, p.point.w[0], p.point.w[1], p.point.w[2], p.position.x(),
        p.position.y(), p.position.z());
  }
  return out + "]}";
}

// The --expmap centre "F W0 W1 W2", or nothing when it is not one line of
// four numbers with an integral F that fits an int32.
std::optional<mesh::SurfacePoint> ParseExpMapCentre(const std::string& text) {
  const absl::StatusOr<std::vector<mesh::NumberLine>> centre = mesh::ParseNumberLines(text, 4);
  if (!centre.ok() || centre->size() != 1 ||
      (*centre)[0].values[0] != std::floor((*centre)[0].values[0]) ||
      !(std::abs((*centre)[0].values[0]) < 2147483648.0)) {
    return std::nullopt;
  }
  const std::vector<double>& c = (*centre)[0].values;
  return mesh::SurfacePoint{static_cast<int32_t>(c[0]), {c[1], c[2], c[3]}};
}

}  // namespace

QueryCommandLine::QueryCommandLine()
    : app_("geodex-query: geodesic queries from an index file, offline.") {
  AddQueryOptions();
  AddAnswerOptions();
}

void QueryCommandLine::AddQueryOptions() {
  QueryToolArgs& a = args_;
  app_.add_option("index", a.index, "Index file (.gdx)")->required();
  auto* pairs =
      app_.add_option("--pairs", a.pairs, "Distances for lines 'fa a0 a1 a2 fb b0 b1 b2'");
  auto* paths = app_.add_option("--paths", a.paths, "Paths for lines 'fa a0 a1 a2 fb b0 b1 b2'");
  auto* field = app_.add_option("--field", a.field, "Distance field from lines 'f w0 w1 w2'");
  auto* locate = app_.add_option("--locate", a.locate, "Closest surface points to lines 'x y z'");
  auto* expmap = app_.add_option("--expmap", a.expmap,
                                 "Exponential map round the point \"F W0 W1 W2\": 'vertex u v' "
                                 "for every vertex within --radius");
  app_.add_option("--radius", a.radius,
                  "With --expmap: the geodesic radius; with --field: only the vertices within it, "
                  "exact, one line 'vertex distance' each (ascending)");
  app_.add_option("--direction", a.direction,
                  "With --expmap: the reference direction X Y Z (theta = 0), projected into "
                  "the centre's face; default its first edge")
      ->expected(3)
      ->needs(expmap);
  auto* info =
      app_.add_flag("--info", a.info,
                    "The index's build report: mesh, samples, size, error target and accuracy by "
                    "distance (--format json: one JSON object)");
  pairs->excludes(paths)->excludes(field)->excludes(locate)->excludes(info)->excludes(expmap);
  paths->excludes(field)->excludes(locate)->excludes(expmap);
  field->excludes(locate)->excludes(expmap);
  locate->excludes(expmap);
}

void QueryCommandLine::AddAnswerOptions() {
  QueryToolArgs& a = args_;
  app_.add_option("--near-pairs", a.near_pairs,
                  "Near pairs (the same or adjacent geodesic triangles, or closer than the "
                  "index's refinement distance, which --info gives in L1000: 'walked or exact "
                  "below N L1000'): path (the traced path's length, default), unfold (pure "
                  "O(1)) or exact (local exact propagation)")
      ->check(CLI::IsMember({"path", "unfold", "exact"}));
  app_.add_flag("--exact-near-pairs", a.exact_near, "Same as --near-pairs exact");
  app_.add_flag("--error-bounds", a.error_bounds,
                "With --pairs: print 'distance bound' per line, bound = the answer's absolute "
                "error bound (needs an index with its accuracy calibration)");
  app_.add_option("--tolerance", a.tolerance,
                  "With --pairs: relative error tolerance (e.g. 0.005): refine every pair whose "
                  "bound exceeds tolerance x distance (0: off)")
      ->check(CLI::NonNegativeNumber);
  app_.add_option("--refine-below", a.refine_below,
                  "With --pairs: refine (as --near-pairs says) every pair that may be closer "
                  "than this many L1000, the spacing of 1,000 samples on the surface (e.g. 8: "
                  "the every-distance mode; 0: the index's own threshold, 3 of its spacings)")
      ->check(CLI::NonNegativeNumber);
  app_.add_option("--exact-path-corridor", a.exact_path_corridor,
                  "With --paths: also solve exactly within this many edge steps of the traced "
                  "path and keep the shorter (not O(k); 0: off)")
      ->check(CLI::Range(0, 64));
  app_.add_flag("--linear-baseline", a.baseline, "The paper's linear interpolation (§6.3)");
  app_.add_flag("--nearest", a.nearest, "With --field: also print the nearest source");
  app_.add_option(
          "--format", a.format,
          "Path output: xyz ('# path I length L', then a line 'x y z' a point, a blank line "
          "between paths) or json ({length, points}); --info: text or json")
      ->check(CLI::IsMember({"xyz", "json", "text"}));
}

query::DistanceOptions DistanceOptionsOf(const QueryToolArgs& args) {
  query::DistanceOptions options;
  options.near_pairs = args.exact_near || args.near_pairs == "exact" ? query::NearPairs::kExact
                       : args.near_pairs == "unfold"                 ? query::NearPairs::kUnfold
                                                                     : query::NearPairs::kPath;
  options.tolerance = args.tolerance;
  options.refine_below_l1000 = args.refine_below;
  return options;
}

// Vertices and faces count the mesh file's; the counts of the mesh the index
// answers on (repaired, refined) follow.
std::string IndexInfoText(const query::InputQueries& queries, const QueryToolArgs& args) {
  const index::IndexReport report = index::MakeIndexReport(queries.index());
  return args.format == "json" ? index::IndexReportJson(report)
                               : index::IndexReportText(report, args.index);
}

absl::StatusOr<std::string> PairDistancesText(const query::InputQueries& queries,
                                              const QueryToolArgs& args,
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

absl::StatusOr<std::string> PathsText(const query::InputQueries& queries,
                                      const QueryToolArgs& args) {
  query::EnginePoints a, b;
  GEODEX_ASSIGN_OR_RETURN(const auto pairs, ReadPairs(queries, args.paths, &a, &b));
  const bool json = args.format == "json";
  std::string out = json ? "[\n" : "";
  for (size_t i = 0; i < pairs.size(); ++i) {
    absl::StatusOr<std::vector<query::PathPoint>> path =
        queries.Path(a, i, b, i, args.exact_path_corridor);
    if (!path.ok()) return AtLine(path.status(), pairs[i].line);
    if (json) {
      out += PathJson(*path) + (i + 1 < pairs.size() ? ",\n" : "\n");
      continue;
    }
    out += absl::StrFormat("# path %d length %.17g\n", i, query::PathLength(*path));
    for (const query::PathPoint& p : *path) {
      out += absl::StrFormat("%.17g %.17g %.17g\n", p.position.x(), p.position.y(), p.position.z());
    }
    out += "\n";
  }
  return json ? out + "]\n" : out;
}

absl::StatusOr<std::string> FieldText(const query::InputQueries& queries,
                                      const QueryToolArgs& args) {
  GEODEX_ASSIGN_OR_RETURN(const std::string text, mesh::ReadFileOrStdin(args.field));
  GEODEX_ASSIGN_OR_RETURN(const auto lines, mesh::ParseNumberLines(text, 4));
  std::vector<mesh::SurfacePoint> points;
  for (const mesh::NumberLine& l : lines) {
    const std::vector<double>& v = l.values;
    points.push_back({static_cast<int32_t>(v[0]), {v[1], v[2], v[3]}});
  }
  query::EnginePoints sources;
  GEODEX_RETURN_IF_ERROR(queries.Read(points, nullptr, &sources));
  std::string out;
  if (args.radius != 0) {
    query::FieldWithinOptions options;
    options.radius = args.radius;
    GEODEX_ASSIGN_OR_RETURN(const query::RadiusField field, queries.FieldWithin(sources, options));
    for (size_t i = 0; i < field.vertices.size(); ++i) {
      absl::StrAppend(&out, field.vertices[i], " ", mesh::FormatDistance(field.distance[i]));
      if (args.nearest) out += absl::StrFormat(" %d", field.nearest[i]);
      out += "\n";
    }
    return out;
  }
  GEODEX_ASSIGN_OR_RETURN(const query::DistanceField field, queries.Field(sources));
  for (size_t v = 0; v < field.distance.size(); ++v) {
    out += mesh::FormatDistance(field.distance[v]);
    if (args.nearest) out += absl::StrFormat(" %d", field.nearest[v]);
    out += "\n";
  }
  return out;
}

absl::StatusOr<std::string> LocateText(const query::InputQueries& queries,
                                       const QueryToolArgs& args) {
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

absl::StatusOr<std::string> ExpMapText(const query::InputQueries& queries,
                                       const QueryToolArgs& args,
                                       const query::DistanceOptions& options) {
  const std::optional<mesh::SurfacePoint> centre = ParseExpMapCentre(args.expmap);
  if (!centre.has_value()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "--expmap wants \"F W0 W1 W2\" (a face id and three weights), got \"%s\"", args.expmap));
  }
  query::ExpMapOptions map_options;
  map_options.radius = args.radius;
  map_options.distance = options;
  if (!args.direction.empty()) {
    map_options.reference_direction =
        mesh::Vec3(args.direction[0], args.direction[1], args.direction[2]);
  }
  query::EnginePoints read;
  GEODEX_RETURN_IF_ERROR(queries.Read(std::span(&*centre, 1), query::PointName(), &read));
  query::QueryScratch scratch;
  GEODEX_ASSIGN_OR_RETURN(const auto map, query::ExpMap(queries, read, 0, map_options, &scratch));
  std::string out;
  for (const query::ExpMapVertex& e : map) {
    out += absl::StrFormat("%d %.17g %.17g\n", e.vertex, e.u, e.v);
  }
  return out;
}

absl::StatusOr<std::string> AnswerQueryTool(const QueryToolArgs& args) {
  query::QueryOptions options;
  options.exact_path_corridor = args.exact_path_corridor;
  GEODEX_ASSIGN_OR_RETURN(const auto queries, query::InputQueries::Open(args.index, options));
  const query::DistanceOptions distance_options = DistanceOptionsOf(args);
  if (args.radius != 0 && args.field.empty() && args.expmap.empty()) {
    return absl::InvalidArgumentError("--radius needs --field or --expmap");
  }
  if (args.info) return IndexInfoText(*queries, args);
  if (!args.pairs.empty()) return PairDistancesText(*queries, args, distance_options);
  if (!args.paths.empty()) return PathsText(*queries, args);
  if (!args.field.empty()) return FieldText(*queries, args);
  if (!args.locate.empty()) return LocateText(*queries, args);
  if (!args.expmap.empty()) return ExpMapText(*queries, args, distance_options);
  return absl::InvalidArgumentError("give one of --pairs, --paths, --field, --locate, --expmap");
}

int QueryExitCode(const absl::Status& status) {
  if (status.ok()) return 0;
  return status.code() == absl::StatusCode::kInvalidArgument ||
                 status.code() == absl::StatusCode::kOutOfRange ||
                 status.code() == absl::StatusCode::kNotFound
             ? 2
             : 1;
}

}  // namespace geodex::tools
