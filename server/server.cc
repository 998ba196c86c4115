#include "server/server.h"

#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include "absl/strings/str_format.h"
#include "grpcpp/ext/proto_server_reflection_plugin.h"
#include "grpcpp/health_check_service_interface.h"
#include "grpcpp/security/server_credentials.h"
#include "grpcpp/server_builder.h"
#include "server/service/parse_error_interceptor.h"
#include "spdlog/spdlog.h"

namespace geodex::server {
namespace {

constexpr char kServiceName[] = "geodex.v1.Geodex";

absl::StatusOr<std::string> ReadPemFile(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrFormat("%s %s: cannot open", what, path));
  std::ostringstream text;
  text << in.rdbuf();
  if (text.str().find("-----BEGIN ") == std::string::npos) {
    return absl::InvalidArgumentError(absl::StrFormat("%s %s: not a PEM file", what, path));
  }
  return text.str();
}

absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> MakeCredentials(const TlsOptions& tls) {
  if (tls.cert_file.empty() && tls.key_file.empty()) {
    if (!tls.ca_file.empty()) {
      return absl::InvalidArgumentError("a client CA (--tls-ca) needs --tls-cert and --tls-key");
    }
    return grpc::InsecureServerCredentials();
  }
  if (tls.cert_file.empty() || tls.key_file.empty()) {
    return absl::InvalidArgumentError("TLS needs both a certificate and a key");
  }
  auto cert = ReadPemFile(tls.cert_file, "TLS certificate");
  if (!cert.ok()) return cert.status();
  auto key = ReadPemFile(tls.key_file, "TLS key");
  if (!key.ok()) return key.status();
  grpc::SslServerCredentialsOptions ssl(GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE);
  if (!tls.ca_file.empty()) {
    auto ca = ReadPemFile(tls.ca_file, "TLS client CA");
    if (!ca.ok()) return ca.status();
    ssl = grpc::SslServerCredentialsOptions(
        GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
    ssl.pem_root_certs = *ca;
  }
  ssl.pem_key_cert_pairs.push_back({*key, *cert});
  return grpc::SslServerCredentials(ssl);
}

}  // namespace

absl::StatusOr<std::unique_ptr<GeodexServer>> GeodexServer::Start(const ServerOptions& options) {
  std::unique_ptr<GeodexServer> server(new GeodexServer());
  if (options.workers < 0) return absl::InvalidArgumentError("workers must be >= 0");
  if (!options.token_file.empty() && !options.token_env.empty()) {
    return absl::InvalidArgumentError("give a token file or a token variable, not both");
  }
  auto credentials = MakeCredentials(options.tls);
  if (!credentials.ok()) return credentials.status();
  if (!options.token_file.empty()) {
    auto auth = TokenAuth::FromFile(options.token_file);
    if (!auth.ok()) return auth.status();
    server->auth_ = std::make_unique<TokenAuth>(*std::move(auth));
  } else if (!options.token_env.empty()) {
    auto auth = TokenAuth::FromEnv(options.token_env);
    if (!auth.ok()) return auth.status();
    server->auth_ = std::make_unique<TokenAuth>(*std::move(auth));
  }

  RegistryOptions registry_options;
  registry_options.root = options.models_dir;
  registry_options.poll_interval = options.poll_interval;
  registry_options.before_load = options.before_load;
  auto registry = ModelRegistry::Create(registry_options);
  if (!registry.ok()) return registry.status();
  server->registry_ = *std::move(registry);

  server->metrics_ = std::make_unique<Metrics>();
  if (!options.metrics_listen.empty()) {
    if (absl::Status s = server->metrics_->Serve(options.metrics_listen); !s.ok()) return s;
  }

  const int workers =
      options.workers > 0 ? options.workers : std::max(1u, std::thread::hardware_concurrency());
  const int64_t queue = options.queue_capacity > 0 ? options.queue_capacity : 256 * workers;
  server->pool_ = std::make_unique<WorkerPool>(workers, queue);
  server->service_ =
      std::make_unique<GeodexService>(server->registry_.get(), server->pool_.get(),
                                      server->metrics_.get(), server->auth_.get(), options.limits);

  // Process-wide switches; they only affect servers built after this point.
  grpc::EnableDefaultHealthCheckService(true);
  if (options.reflection) grpc::reflection::InitProtoReflectionServerBuilderPlugin();

  grpc::ServerBuilder builder;
  builder.AddListeningPort(options.listen, *credentials, &server->port_);
  builder.RegisterService(server->service_.get());
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> interceptors;
  interceptors.push_back(MakeParseErrorInterceptorFactory());
  builder.experimental().SetInterceptorCreators(std::move(interceptors));
  builder.SetMaxReceiveMessageSize(static_cast<int>(
      std::min<int64_t>(options.limits.max_message_bytes, std::numeric_limits<int>::max())));
  server->server_ = builder.BuildAndStart();
  if (server->server_ == nullptr || server->port_ == 0) {
    return absl::UnavailableError(absl::StrFormat(
        "cannot listen on %s (address in use or invalid, or unusable TLS files)", options.listen));
  }
  grpc::HealthCheckServiceInterface* health = server->server_->GetHealthCheckService();
  health->SetServingStatus("", false);           // ready after the first scan
  health->SetServingStatus(kServiceName, true);  // alive

  GeodexServer* self = server.get();
  server->registry_->SetListener(
      [self](const RegistrySnapshot& before, const RegistrySnapshot& after) {
        self->OnRegistryChange(before, after);
      });
  server->registry_->Start();
  spdlog::info(
      "geodex-server listening on port {} ({}), models from {}, {} workers{}{}", server->port_,
      options.tls.cert_file.empty() ? "plaintext"
      : options.tls.ca_file.empty() ? "TLS"
                                    : "mTLS",
      options.models_dir, workers, server->auth_ ? ", bearer tokens required" : "",
      server->metrics_port() > 0 ? absl::StrFormat(", metrics on port %d", server->metrics_port())
                                 : std::string());
  return server;
}

GeodexServer::~GeodexServer() { Shutdown(absl::Seconds(5)); }

std::shared_ptr<grpc::Channel> GeodexServer::InProcessChannel() {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  return server_->InProcessChannel(args);
}

void GeodexServer::OnRegistryChange(const RegistrySnapshot& before, const RegistrySnapshot& after) {
  metrics_->UpdateModels(after);
  std::lock_guard<std::mutex> lock(health_mutex_);
  if (health_frozen_ || server_ == nullptr) return;
  grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService();
  for (const auto& [name, model] : before.models) {
    if (after.models.count(name) == 0) health->SetServingStatus(name, false);
  }
  for (const auto& [name, model] : after.models) {
    health->SetServingStatus(name, !model->served.empty());
  }
  health->SetServingStatus("", after.initial_scan_done);
}

void GeodexServer::Shutdown(absl::Duration drain) {
  std::lock_guard<std::mutex> shutdown_lock(shutdown_mutex_);
  if (shutdown_) return;
  shutdown_ = true;
  if (server_ == nullptr) {  // Start failed half-way
    if (pool_) pool_->Stop();
    if (registry_) registry_->Stop();
    return;
  }
  spdlog::info("shutting down: draining calls for up to {:.1f}s", absl::ToDoubleSeconds(drain));
  {
    std::lock_guard<std::mutex> lock(health_mutex_);
    health_frozen_ = true;
    server_->GetHealthCheckService()->Shutdown();  // everything NOT_SERVING
  }
  // Drain our own calls first: new ones are refused (UNAVAILABLE) while the
  // running ones finish. grpc::Server::Shutdown is called only then, with a
  // deadline already past, because it would otherwise also wait for idle
  // client connections to go away (seconds) after the last call has ended.
  service_->BeginShutdown();
  const auto deadline = std::chrono::steady_clock::now() + absl::ToChronoMilliseconds(drain);
  while (!service_->idle() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (!service_->idle()) spdlog::warn("drain deadline reached; cancelling the remaining calls");
  server_->Shutdown(std::chrono::system_clock::now());
  pool_->Stop();
  registry_->Stop();
  spdlog::info("shut down");
}

void GeodexServer::Wait() { server_->Wait(); }

}  // namespace geodex::server
