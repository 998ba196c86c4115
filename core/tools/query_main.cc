// geodex-query: answers queries offline from an index file, without a server;
// its usage, flags and output are core/tools/query_cli.h.

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
