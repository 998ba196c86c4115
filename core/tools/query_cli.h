#pragma once

// The geodex-query command line (core/tools/query_main.cc): its flags, and
// the text it prints for each kind of query.
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
// from, also when the builder repaired it (core/query/engine/input_ids.h). Output
// goes to standard output in input order; on a bad line nothing is printed and
// the error names the line. Exit codes: 0 ok, 2 bad input, 1 other errors.
//
//   QueryCommandLine  the CLI11 app, its flags bound to a QueryToolArgs
//   AnswerQueryTool   opens the index and answers what the flags ask
//   QueryExitCode     the process's exit status for an error
//
// Every text function answers in the ids of the mesh file the index was
// built from (core/query/input_queries.h) and returns the whole output, so
// that nothing is printed when a line is bad; their errors name the line.
//
// Thread safety: the text functions are reentrant; a QueryCommandLine is
// used by one thread.

#include <cstdint>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/query/input_queries.h"

namespace geodex::tools {

// What geodex-query is asked, as its flags say (defaults as documented in
// QueryCommandLine's help).
struct QueryToolArgs {
  std::string index;  // the .gdx file
  // The query: the first of info, pairs, paths, field, locate, expmap given
  // (CLI11 refuses most pairs of them). Files ("-": standard input), except
  // expmap, the centre "F W0 W1 W2" itself.
  std::string pairs, paths, field, locate, expmap;
  bool info = false;
  // --expmap: the geodesic radius and the reference direction (empty or
  // three numbers). --field with a radius: the field within it.
  double radius = 0;
  std::vector<double> direction;
  std::string format = "xyz";       // --paths: "xyz" or "json"
  std::string near_pairs = "path";  // "path", "unfold" or "exact"
  bool exact_near = false;          // --exact-near-pairs: near_pairs "exact"
  bool baseline = false;            // --linear-baseline
  bool nearest = false;             // --field: also the nearest source
  bool error_bounds = false;        // --pairs: also each answer's bound
  double tolerance = 0;
  double refine_below = 0;  // --refine-below, in L1000 (0: the index's threshold)
  int32_t exact_path_corridor = 0;
};

// The geodex-query app: parsing it (CLI11_PARSE) fills args(); CLI11 checks
// the values it can (ranges, choices, exclusive queries).
class QueryCommandLine {
 public:
  QueryCommandLine();
  QueryCommandLine(const QueryCommandLine&) = delete;
  QueryCommandLine& operator=(const QueryCommandLine&) = delete;

  CLI::App& app() { return app_; }
  const QueryToolArgs& args() const { return args_; }

 private:
  void AddQueryOptions();
  void AddAnswerOptions();

  QueryToolArgs args_;
  CLI::App app_;
};

// The distance options the flags ask for (near pairs, tolerance, the
// refinement threshold).
query::DistanceOptions DistanceOptionsOf(const QueryToolArgs& args);

// The index's build report (core/index/index_report.h) for --info: text
// for a person, or with --format json one JSON object.
std::string IndexInfoText(const query::InputQueries& queries, const QueryToolArgs& args);

// --pairs: "distance" per pair ("distance bound" with error_bounds), in
// input order. Errors: the file's, InvalidArgument/OutOfRange for a bad point
// ("line N: ..."), the queries' errors prefixed with the pair's line.
absl::StatusOr<std::string> PairDistancesText(const query::InputQueries& queries,
                                              const QueryToolArgs& args,
                                              const query::DistanceOptions& options);

// --paths: "x y z" lines with a blank line after each path, or with format
// "json" an array of paths of {"face", "w", "xyz"} points. Errors: as
// PairDistancesText.
absl::StatusOr<std::string> PathsText(const query::InputQueries& queries,
                                      const QueryToolArgs& args);

// --field: a distance per vertex from the sources of the file args.field
// ("distance nearest_source" with nearest); with args.radius, "vertex
// distance [nearest_source]" for the vertices within it only, exact
// (InputQueries::FieldWithin). Errors: the file's, bad points, a radius that
// is not finite and > 0.
absl::StatusOr<std::string> FieldText(const query::InputQueries& queries,
                                      const QueryToolArgs& args);

// --locate: "face w0 w1 w2 distance" per line "x y z" of args.locate.
absl::StatusOr<std::string> LocateText(const query::InputQueries& queries,
                                       const QueryToolArgs& args);

// --expmap: "vertex u v" for every vertex within args.radius of the centre.
// Errors: InvalidArgument for a centre that is not "F W0 W1 W2" with an
// integral F, and the exponential map's.
absl::StatusOr<std::string> ExpMapText(const query::InputQueries& queries,
                                       const QueryToolArgs& args,
                                       const query::DistanceOptions& options);

// Opens args.index and returns what geodex-query prints on standard output.
// Errors: the index's, the query's, InvalidArgument when no query is given.
absl::StatusOr<std::string> AnswerQueryTool(const QueryToolArgs& args);

// 2 for bad input (InvalidArgument, OutOfRange, NotFound), 1 otherwise.
int QueryExitCode(const absl::Status& status);

}  // namespace geodex::tools
