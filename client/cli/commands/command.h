#pragma once

// The verbs of the `geodex` command line, one file each beside this header
// (models.cc, info.cc, distance.cc, ...; the usage of all of them heads
// client/cli/geodex_main.cc).
//
// Add<Verb>Command adds the verb's subcommand to `app` with its flags, in
// the order `--help` lists them: the connection flags every verb has first,
// then the model's (every verb but models and web), then its own. When the
// user chooses that subcommand, parsing runs the verb and stores its Status
// in *status; an input error (IsInputError, command_util.h) maps to exit
// code 2, any other error to 1. The flags' values are owned by the
// subcommand's callback, so they live as long as `app`; `status` must
// outlive the parse.

#include "CLI/CLI.hpp"
#include "absl/status/status.h"

namespace geodex::client::cli {

// The signature every Add<Verb>Command has.
using AddCommand = void (*)(CLI::App* app, absl::Status* status);

void AddModelsCommand(CLI::App* app, absl::Status* status);    // models.cc
void AddInfoCommand(CLI::App* app, absl::Status* status);      // info.cc
void AddDistanceCommand(CLI::App* app, absl::Status* status);  // distance.cc
void AddPathCommand(CLI::App* app, absl::Status* status);      // path.cc
void AddFieldCommand(CLI::App* app, absl::Status* status);     // field.cc
void AddExpMapCommand(CLI::App* app, absl::Status* status);    // expmap.cc
void AddLocateCommand(CLI::App* app, absl::Status* status);    // locate.cc
void AddMatrixCommand(CLI::App* app, absl::Status* status);    // matrix.cc
void AddBenchCommand(CLI::App* app, absl::Status* status);     // bench.cc
void AddWebCommand(CLI::App* app, absl::Status* status);       // web.cc

}  // namespace geodex::client::cli
