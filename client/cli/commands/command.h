#pragma once

// The verbs of the `geodex` command line, one file each beside this header
// (models.cc, info.cc, distance.cc, ...), each headed by what the verb does;
// `geodex --help-all` prints the usage of all of them.
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

// The verbs, written once, in the order `--help` lists them: X(Verb) stands
// for Add<Verb>Command, defined in the verb's file. geodex_main.cc adds them
// all from this list, so a new verb is its file, one line here and one in
// client/CMakeLists.txt.
#define GEODEX_CLI_VERBS(X) \
  X(Models)                 \
  X(Info)                   \
  X(Distance)               \
  X(Path)                   \
  X(Field)                  \
  X(ExpMap)                 \
  X(Locate)                 \
  X(Matrix)                 \
  X(Bench)                  \
  X(Web)

#define GEODEX_CLI_DECLARE_VERB(Verb) void Add##Verb##Command(CLI::App* app, absl::Status* status);
GEODEX_CLI_VERBS(GEODEX_CLI_DECLARE_VERB)
#undef GEODEX_CLI_DECLARE_VERB

}  // namespace geodex::client::cli
