// geodex-query: answers queries offline from an index file, without a server;
// its flags and output are core/tools/query_cli.h.
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
// exponential map, core/query/internal/expmap/exp_map.h), ascending by vertex id. Face and
// vertex ids, in and out, are those of the mesh file the index was built
// from, also when the builder repaired it (core/query/internal/input_ids.h). Output
// goes to standard output in input order; on a bad line nothing is printed and
// the error names the line. Exit codes: 0 ok, 2 bad input, 1 other errors.

#include <cstdio>

#include "CLI/CLI.hpp"
#include "core/tools/query_cli.h"

int main(int argc, char** argv) {
  geodex::tools::QueryCommandLine command_line;
  CLI11_PARSE(command_line.app(), argc, argv);
  const absl::StatusOr<std::string> out = geodex::tools::AnswerQueryTool(command_line.args());
  if (!out.ok()) {
    std::fprintf(stderr, "geodex-query: %s\n", out.status().ToString().c_str());
    return geodex::tools::QueryExitCode(out.status());
  }
  std::fwrite(out->data(), 1, out->size(), stdout);
  return 0;
}
