#pragma once

// Command-line parsing shared by the benchmarks and the soak driver: CLI11's
// parse with its own handling of --help and of bad flags, returned as an exit
// code instead of a `return` from main, so that a program's flags can be
// declared and tested in a library.

#include <iostream>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"

namespace geodex::bench {

// Parses `argv` (argv[0] the program) into the options declared on `app`.
// Returns nullopt when the program should go on, else the exit code CLI11
// gives: 0 after printing the help to `out`, non-zero after printing the
// error and a hint to `err` (the same text and codes as CLI11_PARSE).
std::optional<int> ParseFlags(CLI::App& app, int argc, const char* const* argv,
                              std::ostream& out = std::cout, std::ostream& err = std::cerr);

// The same over `args`, args[0] being the program.
std::optional<int> ParseFlags(CLI::App& app, const std::vector<std::string>& args,
                              std::ostream& out = std::cout, std::ostream& err = std::cerr);

}  // namespace geodex::bench
