#pragma once

// geodex-server assembled: the model registry, the worker pool, the Geodex
// service, the standard gRPC health service (overall "" and one entry per
// model name), server reflection, optional TLS / mTLS and bearer tokens, and
// Prometheus metrics on a port of their own.
//
// Health: "" is SERVING once the first repository scan has finished (use it
// for readiness), "geodex.v1.Geodex" is SERVING from start (use it for
// liveness: a long first scan must not get the process restarted); both are
// NOT_SERVING once Shutdown begins. A model's name is SERVING while at least
// one of its versions is served, NOT_SERVING while it loads, has failed with
// nothing served, or has been removed.
//
// Usage:
//   ServerOptions options;
//   options.models_dir = "/srv/models";
//   options.listen = "0.0.0.0:8980";
//   GEODEX_ASSIGN_OR_RETURN(auto server, GeodexServer::Start(options));
//   ...                                   // SIGTERM arrives
//   server->Shutdown(absl::Seconds(20));
//
// Thread safety: all methods are safe from any thread; Shutdown is
// idempotent.

#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "grpcpp/channel.h"
#include "grpcpp/server.h"
#include "server/config/limits.h"
#include "server/registry/model_registry.h"
#include "server/service/auth.h"
#include "server/geodex_service.h"
#include "server/service/metrics.h"
#include "server/service/worker_pool.h"

namespace geodex::server {

struct TlsOptions {
  std::string cert_file;  // PEM server certificate chain; empty: plaintext
  std::string key_file;   // PEM private key
  std::string ca_file;    // PEM CA bundle: if set, clients must present a
                          // certificate it verifies (mTLS)
};

struct ServerOptions {
  std::string models_dir;
  std::string listen = "127.0.0.1:0";                // port 0 picks a free port (see port())
  std::string metrics_listen;                        // "host:port" for /metrics; empty: none
  int workers = 0;                                   // 0: hardware threads
  int64_t queue_capacity = 0;                        // 0: 256 per worker
  absl::Duration poll_interval = absl::Seconds(10);  // <= 0: SIGHUP / Rescan only
  TlsOptions tls;
  std::string token_file;  // bearer tokens, one a line
  std::string token_env;   // or: the environment variable holding the token
  ServiceLimits limits;
  bool reflection = true;
  // Test hook, see RegistryOptions::before_load.
  std::function<void(const std::string& path)> before_load;
};

class GeodexServer {
 public:
  // Validates options, reads TLS and token files, starts listening and starts
  // loading models in the background (requests for a model still loading get
  // UNAVAILABLE). Errors: InvalidArgument for inconsistent options
  // (key without certificate, ...); NotFound / PermissionDenied for missing
  // files or model directory; Unavailable if an address cannot be bound.
  static absl::StatusOr<std::unique_ptr<GeodexServer>> Start(const ServerOptions& options);
  // Shuts down with a 5 s drain if Shutdown was not called.
  ~GeodexServer();
  GeodexServer(const GeodexServer&) = delete;
  GeodexServer& operator=(const GeodexServer&) = delete;

  // The bound gRPC port.
  int port() const { return port_; }
  // The /metrics port, or -1.
  int metrics_port() const { return metrics_ ? metrics_->port() : -1; }
  // A channel to this server that bypasses the network (same process).
  std::shared_ptr<grpc::Channel> InProcessChannel();

  ModelRegistry& registry() { return *registry_; }
  Metrics& metrics() { return *metrics_; }
  GeodexService& service() { return *service_; }
  WorkerPool& pool() { return *pool_; }

  // Graceful shutdown: health goes NOT_SERVING, new calls are refused,
  // StreamDistances calls drain (see GeodexService::BeginShutdown), and calls
  // still running after `drain` are cancelled. Blocks until every call has
  // ended, then stops the workers and the registry. Idempotent.
  void Shutdown(absl::Duration drain);
  // Blocks until Shutdown has completed.
  void Wait();

 private:
  GeodexServer() = default;
  void OnRegistryChange(const RegistrySnapshot& before, const RegistrySnapshot& after);

  int port_ = 0;
  std::unique_ptr<Metrics> metrics_;
  std::unique_ptr<ModelRegistry> registry_;
  std::unique_ptr<WorkerPool> pool_;
  std::unique_ptr<TokenAuth> auth_;
  std::unique_ptr<GeodexService> service_;
  std::unique_ptr<grpc::Server> server_;

  std::mutex shutdown_mutex_;
  bool shutdown_ = false;
  std::mutex health_mutex_;  // orders health updates against Shutdown
  bool health_frozen_ = false;
};

}  // namespace geodex::server
