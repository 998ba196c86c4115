// geodex-server: serves geodex indexes over gRPC (server/server.h); its flags
// are server/server_command_line.h.
//
//   geodex-server --models DIR --listen ADDR [--metrics ADDR] [--workers N]
//                 [--poll-seconds S] [--tls-cert F --tls-key F [--tls-ca F]]
//                 [--token-file F | --token-env VAR] [limits...]
//
// Signals: SIGHUP rescans the model repository at once; SIGTERM and SIGINT
// shut down gracefully (--drain-seconds). Exit codes: 0 after a clean
// shutdown, 2 for bad flags, 1 if the server cannot start.

#include <signal.h>

#include <cstdio>
#include <memory>
#include <string>

#include "CLI/CLI.hpp"
#include "server/server_command_line.h"
#include "server/registry/mapped_files.h"
#include "server/server.h"
#include "spdlog/sinks/stdout_color_sinks.h"
#include "spdlog/spdlog.h"

namespace {

// Logs go to stderr; stdout carries only the "listening on port N" line.
void SetUpProcess(const std::string& log_level) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("geodex-server"));
  spdlog::set_level(spdlog::level::from_str(log_level));
  signal(SIGPIPE, SIG_IGN);
  geodex::server::InstallSigbusReport();
}

// Signals are taken synchronously by the main thread (sigwait); they are
// blocked before any thread starts so that none receives them
// asynchronously.
sigset_t BlockControlSignals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGHUP);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

// SIGHUP rescans the repository; SIGTERM or SIGINT shuts down within `drain`.
void ServeUntilStopped(geodex::server::GeodexServer& server, const sigset_t& signals,
                       absl::Duration drain) {
  for (;;) {
    int signal = 0;
    if (sigwait(&signals, &signal) != 0) continue;
    if (signal == SIGHUP) {
      spdlog::info("SIGHUP: rescanning the model repository");
      server.registry().TriggerRescan();
      continue;
    }
    spdlog::info("{}: shutting down", signal == SIGTERM ? "SIGTERM" : "SIGINT");
    server.Shutdown(drain);
    return;
  }
}

}  // namespace

int main(int argc, char** argv) {
  geodex::server::ServerCommandLine command_line;
  try {
    command_line.app().parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return command_line.app().exit(e) == 0 ? 0 : 2;
  }
  SetUpProcess(command_line.log_level());
  const sigset_t signals = BlockControlSignals();
  auto server = geodex::server::GeodexServer::Start(command_line.Options());
  if (!server.ok()) {
    std::fprintf(stderr, "geodex-server: %s\n", server.status().ToString().c_str());
    return server.status().code() == absl::StatusCode::kInvalidArgument ? 2 : 1;
  }
  std::printf("listening on port %d\n", (*server)->port());
  std::fflush(stdout);
  ServeUntilStopped(**server, signals, command_line.drain());
  return 0;
}
