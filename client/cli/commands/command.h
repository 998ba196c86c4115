#pragma once

// The verbs of the `geodex` command line, one file each beside this header
// (models.cc, info.cc, distance.cc, ...), each headed by what the verb does;
// `geodex --help-all` prints the usage of all of them.
//
// A verb's AddCommand adds its subcommand to `app` with its flags, in
// the order `--help` lists them: the connection flags every verb has first,
// then the model's (every verb but models and web), then its own. When the
// user chooses that subcommand, parsing runs the verb and stores its Status
// in *status; an input error (IsInputError, command_util.h) maps to exit
// code 2, any other error to 1. The flags' values are owned by the
// subcommand's callback, so they live as long as `app`; `status` must
// outlive the parse.

#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"

namespace geodex::client::cli {

// The signature every Add<Verb>Command has.
using AddCommand = void (*)(CLI::App* app, absl::Status* status);

// Each verb registers itself from its file, at static initialisation:
//   [[maybe_unused]] const bool kRegistered = RegisterVerb(30, AddDistanceCommand);
// `rank` is its place in `--help`, ascending: the verbs' files rank them in
// steps of 10, from models (10) to web (100).
// geodex_main.cc adds every registered verb, so a new verb is its file and
// nothing else. Returns true (a value to initialise the registering constant).
bool RegisterVerb(int rank, AddCommand add);
// The registered verbs' AddCommand, by rank. Call after static
// initialisation (from main).
std::vector<AddCommand> RegisteredVerbs();

}  // namespace geodex::client::cli
