// End-to-end tests of geodex-server's security: bearer tokens, TLS and mutual
// TLS, and the options Start rejects.

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "absl/strings/str_format.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "google/protobuf/descriptor.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/security/credentials.h"
#include "gtest/gtest.h"
#include "server/server_testing.h"

namespace geodex::server {
namespace {

using testing::Context;
using testing::DefaultOptions;
using testing::HealthCheck;
using testing::TestServer;

TEST(ServerTest, BearerTokenIsRequired) {
  testing::TempDir secrets;
  const std::string token_file = secrets.path() + "/tokens";
  std::ofstream(token_file) << "let-me-in\n";
  TestServer ts([&](ServerOptions& o) { o.token_file = token_file; });
  auto channel = ts.TcpChannel();
  auto stub = v1::Geodex::NewStub(channel);
  v1::ListModelsResponse list;
  auto context = Context();
  grpc::Status s = stub->ListModels(context.get(), {}, &list);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  context = Context();
  context->AddMetadata("authorization", "Bearer wrong");
  EXPECT_EQ(stub->ListModels(context.get(), {}, &list).error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  context = Context();
  auto stream = stub->StreamDistances(context.get());
  v1::DistanceResult result;
  EXPECT_FALSE(stream->Read(&result));
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::UNAUTHENTICATED);
  context = Context();
  context->AddMetadata("authorization", "Bearer let-me-in");
  EXPECT_TRUE(stub->ListModels(context.get(), {}, &list).ok());
  EXPECT_EQ(list.models_size(), 2);
  EXPECT_EQ(HealthCheck(channel, ""), 1);  // probes need no token
}

// Runs a shell command quietly; true on exit status 0.
bool Run(const std::string& command) {
  return std::system((command + " >/dev/null 2>&1").c_str()) == 0;
}

// A CA, a server certificate for localhost / 127.0.0.1 and a client
// certificate, made with the openssl command line. False if openssl is
// unavailable.
bool MakeCertificates(const std::string& dir) {
  if (!Run("command -v openssl")) return false;
  std::ofstream(dir + "/server.ext") << "subjectAltName=DNS:localhost,IP:127.0.0.1\n";
  const std::string ec = "-newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes";
  const std::string d = dir + "/";
  return Run("openssl req -x509 " + ec + " -keyout " + d + "ca.key -out " + d +
             "ca.pem -days 2 -subj /CN=geodex-test-ca") &&
         Run("openssl req " + ec + " -keyout " + d + "server.key -out " + d +
             "server.csr -subj /CN=localhost") &&
         Run("openssl x509 -req -in " + d + "server.csr -CA " + d + "ca.pem -CAkey " + d +
             "ca.key -CAcreateserial -out " + d + "server.pem -days 2 -extfile " + d +
             "server.ext") &&
         Run("openssl req " + ec + " -keyout " + d + "client.key -out " + d +
             "client.csr -subj /CN=geodex-test-client") &&
         Run("openssl x509 -req -in " + d + "client.csr -CA " + d + "ca.pem -CAkey " + d +
             "ca.key -CAcreateserial -out " + d + "client.pem -days 2");
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

grpc::Status ListOver(const std::shared_ptr<grpc::Channel>& channel) {
  auto stub = v1::Geodex::NewStub(channel);
  v1::ListModelsResponse list;
  auto context = Context(5);
  return stub->ListModels(context.get(), {}, &list);
}

std::shared_ptr<grpc::Channel> TlsChannel(int port, const std::string& dir, bool client_cert) {
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = ReadFile(dir + "/ca.pem");
  if (client_cert) {
    ssl.pem_private_key = ReadFile(dir + "/client.key");
    ssl.pem_cert_chain = ReadFile(dir + "/client.pem");
  }
  return grpc::CreateChannel(absl::StrFormat("localhost:%d", port), grpc::SslCredentials(ssl));
}

TEST(ServerTest, TlsAndMutualTls) {
  testing::TempDir certs;
  if (!MakeCertificates(certs.path())) GTEST_SKIP() << "openssl is not available";
  const std::string d = certs.path() + "/";
  {
    TestServer ts([&](ServerOptions& o) {
      o.listen = "localhost:0";
      o.tls = {d + "server.pem", d + "server.key", ""};
    });
    const int port = ts.server().port();
    EXPECT_TRUE(ListOver(TlsChannel(port, certs.path(), false)).ok());
    // A plaintext client cannot talk to a TLS server.
    EXPECT_FALSE(ListOver(grpc::CreateChannel(absl::StrFormat("localhost:%d", port),
                                              grpc::InsecureChannelCredentials()))
                     .ok());
  }
  {
    TestServer ts([&](ServerOptions& o) {
      o.listen = "localhost:0";
      o.tls = {d + "server.pem", d + "server.key", d + "ca.pem"};
    });
    const int port = ts.server().port();
    EXPECT_FALSE(ListOver(TlsChannel(port, certs.path(), false)).ok());  // no client cert
    EXPECT_TRUE(ListOver(TlsChannel(port, certs.path(), true)).ok());
  }
}

TEST(ServerTest, StartRejectsBadOptions) {
  testing::TempDir dir;
  ServerOptions options = DefaultOptions(dir.path());
  options.tls.cert_file = dir.path() + "/missing.pem";
  EXPECT_FALSE(GeodexServer::Start(options).ok());
  options = DefaultOptions(dir.path());
  options.tls.ca_file = dir.path() + "/ca.pem";
  EXPECT_EQ(GeodexServer::Start(options).status().code(), absl::StatusCode::kInvalidArgument);
  options = DefaultOptions(dir.path() + "/missing");
  EXPECT_EQ(GeodexServer::Start(options).status().code(), absl::StatusCode::kNotFound);
  options = DefaultOptions(dir.path());
  options.token_file = dir.path() + "/missing";
  EXPECT_EQ(GeodexServer::Start(options).status().code(), absl::StatusCode::kNotFound);
  options = DefaultOptions(dir.path());
  options.listen = "256.1.1.1:1";
  EXPECT_EQ(GeodexServer::Start(options).status().code(), absl::StatusCode::kUnavailable);
}

// Bytes that are not a protobuf message of the method's request type: gRPC's
// callback handlers would answer UNIMPLEMENTED (the method does not exist);
// the server says INVALID_ARGUMENT and keeps serving. An unknown method is
// still UNIMPLEMENTED.
TEST(ServerTest, RequestBytesThatDoNotParseAreInvalidArgument) {
  TestServer ts;
  auto channel = ts.TcpChannel();
  const std::string garbage("\xff\xff\xff\x0f", 4);
  // Every method that takes one request message, from the service's
  // descriptor, so that a new one is covered without a change here.
  const google::protobuf::ServiceDescriptor* service =
      google::protobuf::DescriptorPool::generated_pool()->FindServiceByName(
          v1::Geodex::service_full_name());
  ASSERT_NE(service, nullptr);
  for (int i = 0; i < service->method_count(); ++i) {
    if (service->method(i)->client_streaming()) continue;
    const std::string method =
        absl::StrFormat("/%s/%s", service->full_name(), service->method(i)->name());
    auto [status, response] = testing::RawUnary(channel, method, garbage);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << method;
    EXPECT_NE(status.error_message().find("not a valid protobuf message"), std::string::npos)
        << method << ": " << status.error_message();
  }
  auto [unknown, unused] = testing::RawUnary(channel, "/geodex.v1.Geodex/NoSuchMethod", garbage);
  EXPECT_EQ(unknown.error_code(), grpc::StatusCode::UNIMPLEMENTED);
  // A valid (empty) request still works.
  auto [ok, models] = testing::RawUnary(channel, "/geodex.v1.Geodex/ListModels", "");
  EXPECT_TRUE(ok.ok()) << ok.error_message();
  EXPECT_FALSE(models.empty());
}

}  // namespace
}  // namespace geodex::server
