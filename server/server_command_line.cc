#include "server/server_command_line.h"

namespace geodex::server {

ServerCommandLine::ServerCommandLine()
    : app_("geodex-server: constant-time geodesic distance queries over gRPC") {
  // No default address: --listen is required.
  options_.listen.clear();
  AddServingOptions();
  AddSecurityOptions();
  AddLimitOptions();
  app_.add_flag("!--no-reflection", options_.reflection, "Disable gRPC server reflection");
  app_.add_option("--log-level", log_level_, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
}

void ServerCommandLine::AddServingOptions() {
  app_.add_option("--models", options_.models_dir,
                  "Model repository DIR/<model>/<version>/index.gdx")
      ->required()
      ->check(CLI::ExistingDirectory);
  app_.add_option("--listen", options_.listen, "gRPC address, e.g. 0.0.0.0:8980")->required();
  app_.add_option("--metrics", options_.metrics_listen,
                  "Prometheus /metrics address, e.g. 0.0.0.0:9090");
  app_.add_option("--workers", options_.workers, "Query worker threads (0: one per core)")
      ->check(CLI::Range(0, 4096));
  app_.add_option("--queue", options_.queue_capacity,
                  "Jobs that may wait for a worker before RESOURCE_EXHAUSTED (0: 256 per worker)")
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 30));
  app_.add_option("--poll-seconds", poll_seconds_, "Repository poll interval (0: only on SIGHUP)")
      ->check(CLI::Range(0.0, 86400.0));
  app_.add_option("--drain-seconds", drain_seconds_, "Graceful shutdown deadline")
      ->check(CLI::Range(0.0, 3600.0));
}

void ServerCommandLine::AddSecurityOptions() {
  auto* cert = app_.add_option("--tls-cert", options_.tls.cert_file, "PEM server certificate chain")
                   ->check(CLI::ExistingFile);
  auto* key = app_.add_option("--tls-key", options_.tls.key_file, "PEM private key")
                  ->check(CLI::ExistingFile);
  cert->needs(key);
  key->needs(cert);
  app_.add_option("--tls-ca", options_.tls.ca_file,
                  "PEM CA bundle: require client certificates (mTLS)")
      ->check(CLI::ExistingFile)
      ->needs(cert);
  auto* token_file =
      app_.add_option("--token-file", options_.token_file,
                      "Bearer tokens, one a line; calls without one fail UNAUTHENTICATED")
          ->check(CLI::ExistingFile);
  auto* token_env = app_.add_option("--token-env", options_.token_env,
                                    "Environment variable holding the bearer token");
  token_file->excludes(token_env);
}

void ServerCommandLine::AddLimitOptions() {
  ServiceLimits& limits = options_.limits;
  const CLI::Range kPositive(int64_t{1}, int64_t{1} << 40);
  app_.add_option("--max-pairs", limits.max_pairs_per_message,
                  "Pairs per Distance call or stream batch")
      ->check(kPositive);
  app_.add_option("--max-matrix-cells", limits.max_matrix_cells,
                  "Sources x targets per Matrix call")
      ->check(kPositive);
  app_.add_option("--max-field-sources", limits.max_field_sources, "Sources per DistanceField call")
      ->check(kPositive);
  app_.add_option("--max-field-vertices", limits.max_field_vertices,
                  "Vertices a DistanceField call with a radius may reach")
      ->check(kPositive);
  app_.add_option("--max-path-pairs", limits.max_path_pairs, "Pairs per Path call")
      ->check(kPositive);
  app_.add_option("--max-locate", limits.max_locate_positions, "Positions per Locate call")
      ->check(kPositive);
  app_.add_option("--max-message-mib", max_message_mib_, "Largest request message (MiB)")
      ->check(CLI::Range(1, 2047));
  app_.add_option("--max-streams", limits.max_concurrent_streams, "Concurrent streaming calls")
      ->check(kPositive);
  app_.add_option("--stream-window", limits.stream_window,
                  "StreamDistances batches read ahead of the answers written")
      ->check(CLI::Range(1, 1024));
}

ServerOptions ServerCommandLine::Options() const {
  ServerOptions options = options_;
  options.limits.max_message_bytes = max_message_mib_ << 20;
  options.poll_interval = absl::Seconds(poll_seconds_);
  return options;
}

}  // namespace geodex::server
