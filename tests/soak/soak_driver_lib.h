#pragma once

// The pieces of soak_driver (soak_driver.cc): its flags, the --version
// specs, the reference engines, the summary line and the verdict.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/statusor.h"
#include "core/query/engine/query_engine.h"
#include "tests/soak/soak_client.h"

namespace geodex::soak {

struct SoakOptions {
  std::string server;                 // geodex-server address
  std::string model;                  // model name
  std::vector<std::string> versions;  // "V=INDEX": the index of version V
  int threads = 8;                    // concurrent clients
  double seconds = 30;                // run time
  int64_t max_pairs = 1000;           // the server's --max-pairs
};

// The command line of soak_driver, writing into `options` when parsed.
std::unique_ptr<CLI::App> SoakFlags(SoakOptions* options);

// The version and the index path of a --version spec "V=INDEX". Errors:
// InvalidArgument ("--version wants V=INDEX, got ...") without '=' or with a
// V that is not an integer.
absl::StatusOr<std::pair<int64_t, std::string>> ParseVersionSpec(const std::string& spec);

// The offline engine of every --version spec. Errors: a bad spec
// (ParseVersionSpec), or the index's or the engine's error, the message
// ready to print.
absl::StatusOr<std::map<int64_t, std::shared_ptr<const query::QueryEngine>>> LoadEngines(
    const std::vector<std::string>& specs);

// The one line of counts a run prints, with its newline.
std::string SummaryLine(int threads, double seconds, const SoakTotals& totals);

// A run's exit code: 1 on any violation, or when no valid or no invalid call
// was made (nothing was checked: then `failure` gets the line saying so),
// else 0.
int Verdict(const SoakTotals& totals, std::string* failure);

// Runs the whole soak as the command line asks and returns the exit code:
// Verdict's, or 2 when a --version spec or its index is bad.
int RunSoak(const SoakOptions& options);

}  // namespace geodex::soak
