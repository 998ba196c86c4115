#include "client/grpc_connection.h"

#include <arpa/inet.h>

#include <fstream>
#include <sstream>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/status_conversion.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "grpcpp/grpcpp.h"

namespace geodex::client {
namespace {

absl::StatusOr<std::string> ReadPem(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat("cannot read ", what, " file ", path));
  std::ostringstream contents;
  contents << in.rdbuf();
  if (contents.str().empty()) {
    return absl::InvalidArgumentError(absl::StrCat(what, " file ", path, " is empty"));
  }
  return contents.str();
}

// The IP address part of "1.2.3.4:50051" or "[::1]:50051", and its family
// (4 or 6); 0 if `address` is not an IP literal with a port.
int IpFamily(const std::string& address) {
  const size_t colon = address.rfind(':');
  if (colon == std::string::npos || colon + 1 == address.size()) return 0;
  const std::string port = address.substr(colon + 1);
  if (port.find_first_not_of("0123456789") != std::string::npos) return 0;
  std::string host = address.substr(0, colon);
  unsigned char buffer[16];
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
    return inet_pton(AF_INET6, host.c_str(), buffer) == 1 ? 6 : 0;
  }
  return inet_pton(AF_INET, host.c_str(), buffer) == 1 ? 4 : 0;
}

class GrpcDistanceStream : public DistanceStream {
 public:
  GrpcDistanceStream(std::unique_ptr<grpc::ClientContext> context, v1::Geodex::Stub& stub)
      : context_(std::move(context)), stream_(stub.StreamDistances(context_.get())) {}

  ~GrpcDistanceStream() override {
    // gRPC wants every call finished; an abandoned stream is cancelled first so
    // that Finish does not wait for the server.
    if (!finished_) {
      context_->TryCancel();
      stream_->Finish();
    }
  }

  bool Write(const v1::DistanceBatch& batch) override { return stream_->Write(batch); }
  bool WritesDone() override { return stream_->WritesDone(); }
  bool Read(v1::DistanceResult* result) override { return stream_->Read(result); }
  void Cancel() override { context_->TryCancel(); }
  absl::Status Finish() override {
    finished_ = true;
    return FromGrpcStatus(stream_->Finish());
  }

 private:
  std::unique_ptr<grpc::ClientContext> context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::DistanceBatch, v1::DistanceResult>> stream_;
  bool finished_ = false;
};

class GrpcConnection : public GeodexConnection {
 public:
  GrpcConnection(std::shared_ptr<grpc::Channel> channel, absl::Duration deadline,
                 std::string authorization)
      : channel_(std::move(channel)),
        stub_(v1::Geodex::NewStub(channel_)),
        deadline_(deadline),
        authorization_(std::move(authorization)) {}

  // Call picks the unary or the server-streaming overload from the stub
  // method's signature.
#define GEODEX_CLIENT_GRPC_RPC(Name, Request, Result)            \
  absl::StatusOr<Result> Name(const Request& request) override { \
    return Call(request, &v1::Geodex::Stub::Name);               \
  }
  GEODEX_CLIENT_RPCS(GEODEX_CLIENT_GRPC_RPC)
#undef GEODEX_CLIENT_GRPC_RPC

  std::unique_ptr<DistanceStream> StreamDistances(const StreamOptions& options) override {
    return std::make_unique<GrpcDistanceStream>(MakeContext(options.deadline.value_or(deadline_)),
                                                *stub_);
  }

 private:
  std::unique_ptr<grpc::ClientContext> MakeContext(absl::Duration deadline) const {
    auto context = std::make_unique<grpc::ClientContext>();
    if (deadline != absl::InfiniteDuration()) {
      context->set_deadline(absl::ToChronoTime(absl::Now() + deadline));
    }
    if (!authorization_.empty()) context->AddMetadata("authorization", authorization_);
    return context;
  }

  template <typename Request, typename Response>
  absl::StatusOr<Response> Call(const Request& request,
                                grpc::Status (v1::Geodex::Stub::*method)(grpc::ClientContext*,
                                                                         const Request&,
                                                                         Response*)) {
    auto context = MakeContext(deadline_);
    Response response;
    const grpc::Status status = ((*stub_).*method)(context.get(), request, &response);
    if (!status.ok()) return FromGrpcStatus(status);
    return response;
  }

  template <typename Message, typename Request>
  absl::StatusOr<std::vector<Message>> Call(
      const Request& request,
      std::unique_ptr<grpc::ClientReader<Message>> (v1::Geodex::Stub::*method)(grpc::ClientContext*,
                                                                               const Request&)) {
    auto context = MakeContext(deadline_);
    std::unique_ptr<grpc::ClientReader<Message>> reader =
        ((*stub_).*method)(context.get(), request);
    std::vector<Message> messages;
    Message message;
    while (reader->Read(&message)) messages.push_back(std::move(message));
    const grpc::Status status = reader->Finish();
    if (!status.ok()) return FromGrpcStatus(status);
    return messages;
  }

  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Geodex::Stub> stub_;
  absl::Duration deadline_;
  std::string authorization_;  // "Bearer ..." as metadata (plaintext channels only)
};

}  // namespace

absl::StatusOr<std::string> NormalizeTarget(const std::string& target) {
  if (target.empty()) return absl::InvalidArgumentError("the server address is empty");
  if (target.find(',') == std::string::npos) return target;
  // Anything with a scheme ("ipv4:", "dns:///", ...) is gRPC's business.
  const size_t colon = target.find(':');
  const std::string scheme = target.substr(0, colon);
  if (scheme == "ipv4" || scheme == "ipv6" || scheme == "dns" || scheme == "unix" ||
      absl::StrContains(target, "://")) {
    return target;
  }
  std::vector<std::string> addresses = absl::StrSplit(target, ',', absl::SkipWhitespace());
  int family = 0;
  for (std::string& address : addresses) {
    address.erase(0, address.find_first_not_of(" \t"));
    address.erase(address.find_last_not_of(" \t") + 1);
    const int f = IpFamily(address);
    if (f == 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("'", address,
                       "' in the address list is not an IP address with a port; a list takes "
                       "IP literals only (use dns:///NAME:PORT for all addresses of a name)"));
    }
    if (family != 0 && f != family) {
      return absl::InvalidArgumentError("an address list must not mix IPv4 and IPv6");
    }
    family = f;
  }
  return absl::StrCat(family == 4 ? "ipv4:" : "ipv6:", absl::StrJoin(addresses, ","));
}

absl::StatusOr<std::shared_ptr<GeodexConnection>> MakeGrpcConnectionNoRetry(
    const std::string& target, const ConnectOptions& options) {
  absl::StatusOr<std::string> grpc_target = NormalizeTarget(target);
  if (!grpc_target.ok()) return grpc_target.status();

  const TlsOptions& tls = options.tls;
  const bool use_tls =
      tls.enabled || !tls.ca_file.empty() || !tls.cert_file.empty() || !tls.key_file.empty();
  if (tls.cert_file.empty() != tls.key_file.empty()) {
    return absl::InvalidArgumentError(
        "mutual TLS needs both a client certificate and its private key");
  }
  for (const char c : options.bearer_token) {
    if (c < 0x20 || c > 0x7e) {
      return absl::InvalidArgumentError(
          "the bearer token holds characters not allowed in a header");
    }
  }

  std::shared_ptr<grpc::ChannelCredentials> credentials;
  std::string authorization;
  if (use_tls) {
    grpc::SslCredentialsOptions ssl;
    if (!tls.ca_file.empty()) {
      absl::StatusOr<std::string> pem = ReadPem(tls.ca_file, "CA certificate");
      if (!pem.ok()) return pem.status();
      ssl.pem_root_certs = *std::move(pem);
    }
    if (!tls.cert_file.empty()) {
      absl::StatusOr<std::string> cert = ReadPem(tls.cert_file, "client certificate");
      if (!cert.ok()) return cert.status();
      absl::StatusOr<std::string> key = ReadPem(tls.key_file, "client key");
      if (!key.ok()) return key.status();
      ssl.pem_cert_chain = *std::move(cert);
      ssl.pem_private_key = *std::move(key);
    }
    credentials = grpc::SslCredentials(ssl);
    if (!options.bearer_token.empty()) {
      // gRPC sends call credentials only over channels that protect them.
      credentials = grpc::CompositeChannelCredentials(
          credentials, grpc::AccessTokenCredentials(options.bearer_token));
    }
  } else {
    credentials = grpc::InsecureChannelCredentials();
    if (!options.bearer_token.empty()) authorization = "Bearer " + options.bearer_token;
  }

  grpc::ChannelArguments args;
  if (!options.load_balancing_policy.empty()) {
    args.SetLoadBalancingPolicyName(options.load_balancing_policy);
  }
  if (!options.user_agent_prefix.empty()) args.SetUserAgentPrefix(options.user_agent_prefix);
  if (use_tls && !tls.server_name.empty()) args.SetSslTargetNameOverride(tls.server_name);
  // Path responses and server-chosen blocks can exceed gRPC's 4 MiB default.
  args.SetMaxReceiveMessageSize(256 << 20);

  std::shared_ptr<grpc::Channel> channel =
      grpc::CreateCustomChannel(*grpc_target, credentials, args);
  return std::shared_ptr<GeodexConnection>(
      std::make_shared<GrpcConnection>(std::move(channel), options.deadline, authorization));
}

}  // namespace geodex::client
