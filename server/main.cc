// geodex-server: serves geodex indexes over gRPC (server/server.h).
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
#include <string>

#include "CLI/CLI.hpp"
#include "server/mapped_files.h"
#include "server/server.h"
#include "spdlog/sinks/stdout_color_sinks.h"
#include "spdlog/spdlog.h"

int main(int argc, char** argv) {
  using geodex::server::GeodexServer;
  using geodex::server::ServerOptions;

  ServerOptions options;
  options.listen.clear();
  double poll_seconds = 10;
  double drain_seconds = 20;
  int64_t max_message_mib = options.limits.max_message_bytes >> 20;
  std::string log_level = "info";

  const CLI::Range kPositive(int64_t{1}, int64_t{1} << 40);
  CLI::App app{"geodex-server: constant-time geodesic distance queries over gRPC"};
  app.add_option("--models", options.models_dir, "Model repository DIR/<model>/<version>/index.gdx")
      ->required()
      ->check(CLI::ExistingDirectory);
  app.add_option("--listen", options.listen, "gRPC address, e.g. 0.0.0.0:8980")->required();
  app.add_option("--metrics", options.metrics_listen,
                 "Prometheus /metrics address, e.g. 0.0.0.0:9090");
  app.add_option("--workers", options.workers, "Query worker threads (0: one per core)")
      ->check(CLI::Range(0, 4096));
  app.add_option("--queue", options.queue_capacity,
                 "Jobs that may wait for a worker before RESOURCE_EXHAUSTED (0: 256 per worker)")
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 30));
  app.add_option("--poll-seconds", poll_seconds, "Repository poll interval (0: only on SIGHUP)")
      ->check(CLI::Range(0.0, 86400.0));
  app.add_option("--drain-seconds", drain_seconds, "Graceful shutdown deadline")
      ->check(CLI::Range(0.0, 3600.0));
  auto* cert = app.add_option("--tls-cert", options.tls.cert_file, "PEM server certificate chain")
                   ->check(CLI::ExistingFile);
  auto* key = app.add_option("--tls-key", options.tls.key_file, "PEM private key")
                  ->check(CLI::ExistingFile);
  cert->needs(key);
  key->needs(cert);
  app.add_option("--tls-ca", options.tls.ca_file,
                 "PEM CA bundle: require client certificates (mTLS)")
      ->check(CLI::ExistingFile)
      ->needs(cert);
  auto* token_file =
      app.add_option("--token-file", options.token_file,
                     "Bearer tokens, one a line; calls without one fail UNAUTHENTICATED")
          ->check(CLI::ExistingFile);
  auto* token_env = app.add_option("--token-env", options.token_env,
                                   "Environment variable holding the bearer token");
  token_file->excludes(token_env);
  app.add_option("--max-pairs", options.limits.max_pairs_per_message,
                 "Pairs per Distance call or stream batch")
      ->check(kPositive);
  app.add_option("--max-matrix-cells", options.limits.max_matrix_cells,
                 "Sources x targets per Matrix call")
      ->check(kPositive);
  app.add_option("--max-field-sources", options.limits.max_field_sources,
                 "Sources per DistanceField call")
      ->check(kPositive);
  app.add_option("--max-path-pairs", options.limits.max_path_pairs, "Pairs per Path call")
      ->check(kPositive);
  app.add_option("--max-locate", options.limits.max_locate_positions, "Positions per Locate call")
      ->check(kPositive);
  app.add_option("--max-message-mib", max_message_mib, "Largest request message (MiB)")
      ->check(CLI::Range(1, 2047));
  app.add_option("--max-streams", options.limits.max_concurrent_streams,
                 "Concurrent streaming calls")
      ->check(kPositive);
  app.add_option("--stream-window", options.limits.stream_window,
                 "StreamDistances batches read ahead of the answers written")
      ->check(CLI::Range(1, 1024));
  app.add_flag("!--no-reflection", options.reflection, "Disable gRPC server reflection");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  options.limits.max_message_bytes = max_message_mib << 20;
  options.poll_interval = absl::Seconds(poll_seconds);
  // Logs go to stderr; stdout carries only the "listening on port N" line.
  spdlog::set_default_logger(spdlog::stderr_color_mt("geodex-server"));
  spdlog::set_level(spdlog::level::from_str(log_level));
  signal(SIGPIPE, SIG_IGN);
  geodex::server::InstallSigbusReport();

  // Signals are taken synchronously by this thread (sigwait); block them
  // before any thread starts so that none receives them asynchronously.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGHUP);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  auto server = GeodexServer::Start(options);
  if (!server.ok()) {
    std::fprintf(stderr, "geodex-server: %s\n", server.status().ToString().c_str());
    return server.status().code() == absl::StatusCode::kInvalidArgument ? 2 : 1;
  }
  std::printf("listening on port %d\n", (*server)->port());
  std::fflush(stdout);
  for (;;) {
    int signal = 0;
    if (sigwait(&signals, &signal) != 0) continue;
    if (signal == SIGHUP) {
      spdlog::info("SIGHUP: rescanning the model repository");
      (*server)->registry().TriggerRescan();
      continue;
    }
    spdlog::info("{}: shutting down", signal == SIGTERM ? "SIGTERM" : "SIGINT");
    (*server)->Shutdown(absl::Seconds(drain_seconds));
    return 0;
  }
}
