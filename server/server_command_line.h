#pragma once

// The geodex-server command line (server/main.cc): its flags, and the
// ServerOptions they resolve to.
//
// Thread safety: a ServerCommandLine is used by one thread.

#include <cstdint>
#include <string>

#include "CLI/CLI.hpp"
#include "absl/time/time.h"
#include "server/server.h"

namespace geodex::server {

// The geodex-server app: parsing it (CLI11) fills the options; CLI11 checks
// ranges, existing files and directories, and which flags need or exclude
// others (--tls-cert with --tls-key, --token-file or --token-env).
class ServerCommandLine {
 public:
  ServerCommandLine();
  ServerCommandLine(const ServerCommandLine&) = delete;
  ServerCommandLine& operator=(const ServerCommandLine&) = delete;

  CLI::App& app() { return app_; }

  // After parsing: the server's options, with the message limit in bytes and
  // the repository poll interval as durations.
  ServerOptions Options() const;
  // After parsing: the graceful shutdown deadline (--drain-seconds).
  absl::Duration drain() const { return absl::Seconds(drain_seconds_); }
  // After parsing: spdlog's level name (trace, debug, info, warn, error).
  const std::string& log_level() const { return log_level_; }

 private:
  void AddServingOptions();
  void AddSecurityOptions();
  void AddLimitOptions();

  ServerOptions options_;
  double poll_seconds_ = 10;
  double drain_seconds_ = 20;
  int64_t max_message_mib_ = options_.limits.max_message_bytes >> 20;
  std::string log_level_ = "info";
  CLI::App app_;
};

}  // namespace geodex::server
