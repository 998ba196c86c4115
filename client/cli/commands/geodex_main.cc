// geodex: the command-line client of a geodex server.
//
//   geodex VERB [flags]     e.g. geodex distance --model M --pairs FILE
//   geodex --help-all       every verb with its flags
//
// Every subcommand takes --server ADDR (default $GEODEX_SERVER, else
// localhost:50051), --tls-ca/--tls-cert/--tls-key, --token/--token-file and
// --timeout. Input lines are those of geodex-query (client/cli/text_io.h).
// Results go to standard output (or --out), errors to standard error. Each
// verb, its flags and what it writes, is in client/cli/commands/<verb>.cc;
// the list of verbs and the interface they share are in
// client/cli/commands/command.h.
//
// Exit codes: 0 success; 2 bad usage or bad input, found before anything was
// asked of the server (unreadable or malformed file, with its line number;
// a face id past the model's end; weights that are not barycentric); 1 any
// error from the server or the network (NOT_FOUND for an unknown model,
// UNAVAILABLE, ...) and local I/O errors on output.

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"

namespace geodex::client::cli {

namespace {

// Filled at static initialisation, before Main reads it: a function-local
// static, so that its construction comes before the first registration
// whatever the order of the files.
std::vector<std::pair<int, AddCommand>>& Verbs() {
  static auto* verbs = new std::vector<std::pair<int, AddCommand>>();
  return *verbs;
}

}  // namespace

bool RegisterVerb(int rank, AddCommand add) {
  Verbs().emplace_back(rank, add);
  return true;
}

std::vector<AddCommand> RegisteredVerbs() {
  std::vector<std::pair<int, AddCommand>> verbs = Verbs();
  std::stable_sort(verbs.begin(), verbs.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<AddCommand> out;
  for (const auto& [rank, add] : verbs) out.push_back(add);
  return out;
}

namespace {

int Main(int argc, char** argv) {
  CLI::App app{
      "geodex: geodesic distances, paths and distance fields from a geodex server.\n"
      "Exit codes: 0 ok, 2 bad usage or input (with the line), 1 server or network errors."};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for every subcommand");

  // The chosen verb runs while parsing and leaves its outcome here.
  absl::Status status;
  for (AddCommand add : RegisteredVerbs()) add(&app, &status);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help or the error
    return code == 0 ? 0 : 2;
  }
  if (status.ok()) return 0;
  std::fprintf(stderr, "geodex: %s: %s\n", absl::StatusCodeToString(status.code()).c_str(),
               std::string(status.message()).c_str());
  return IsInputError(status) ? 2 : 1;
}

}  // namespace
}  // namespace geodex::client::cli

int main(int argc, char** argv) { return geodex::client::cli::Main(argc, argv); }
