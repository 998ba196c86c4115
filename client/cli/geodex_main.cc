// geodex: the command-line client of a geodex server.
//
//   geodex models                                   models the server knows
//   geodex info --model M [--format text|json]      one model and its build report
//   geodex distance --model M --pairs FILE|- [--xyz] [--near-pairs MODE] [--tolerance X]
//                   [--error-bounds]
//   geodex path --model M --pairs FILE --format obj|ply|json --out F
//   geodex field --model M --sources FILE --out field.txt|field.ply
//   geodex locate --model M --points FILE
//   geodex expmap --model M --center "F W0 W1 W2" --radius R [--direction X Y Z]
//                 [--out decal.obj|map.txt] [--image IMG] [--png view.png]
//   geodex matrix --model M --sources FILE --targets FILE [--near-pairs MODE]
//   geodex bench --model M --concurrency C --duration S --batch B
//   geodex web --listen HOST:PORT [--assets DIR]   the viewer and an HTTP/JSON gateway
//
// Every subcommand takes --server ADDR (default $GEODEX_SERVER, else
// localhost:50051), --tls-ca/--tls-cert/--tls-key, --token/--token-file and
// --timeout. Input lines are those of geodex-query (client/cli/text_io.h).
// Results go to standard output (or --out), errors to standard error. Each
// verb, its flags and what it writes, is in client/cli/commands/<verb>.cc
// (the interface they share: client/cli/commands/command.h).
//
// Exit codes: 0 success; 2 bad usage or bad input, found before anything was
// asked of the server (unreadable or malformed file, with its line number;
// a face id past the model's end; weights that are not barycentric); 1 any
// error from the server or the network (NOT_FOUND for an unknown model,
// UNAVAILABLE, ...) and local I/O errors on output.

#include <cstdio>
#include <string>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"

namespace geodex::client::cli {
namespace {

int Main(int argc, char** argv) {
  CLI::App app{
      "geodex: geodesic distances, paths and distance fields from a geodex server.\n"
      "Exit codes: 0 ok, 2 bad usage or input (with the line), 1 server or network errors."};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for every subcommand");

  // The chosen verb runs while parsing and leaves its outcome here. The verbs
  // are listed by --help in this order.
  absl::Status status;
  for (AddCommand add :
       {AddModelsCommand, AddInfoCommand, AddDistanceCommand, AddPathCommand, AddFieldCommand,
        AddExpMapCommand, AddLocateCommand, AddMatrixCommand, AddBenchCommand, AddWebCommand}) {
    add(&app, &status);
  }

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
