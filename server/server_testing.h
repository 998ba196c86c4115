#pragma once

// Fixtures of the end-to-end server tests (server_*_test.cc): a real
// GeodexServer over a temporary model repository, the reference engine to
// compare its answers with, and small helpers for requests and raw calls.
// The index builders and the repository helpers are in server/model_repository_testing.h.
//
// Not thread-safe unless stated.

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>

#include "core/query/engine/query_engine.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "grpcpp/channel.h"
#include "grpcpp/client_context.h"
#include "gtest/gtest.h"
#include "server/server.h"
#include "server/model_repository_testing.h"

namespace geodex::server::testing {

// The engine the server should agree with, over the same index bytes.
std::shared_ptr<const query::QueryEngine> ReferenceEngine(const std::string& bytes);

// A loopback server on an ephemeral port, 2 workers, no polling (tests
// rescan explicitly).
ServerOptions DefaultOptions(const std::string& models);

// A server over a repository holding "sphere" (v1) and "torus" (v1), unless
// `write_models` is false. `configure` adjusts the options before the start.
class TestServer {
 public:
  explicit TestServer(std::function<void(ServerOptions&)> configure = nullptr,
                      bool write_models = true);
  GeodexServer& server() { return *server_; }
  const std::string& root() const { return dir_.path(); }
  std::string address() const;
  // A loopback channel without a receive size limit.
  std::shared_ptr<grpc::Channel> TcpChannel();
  void Rescan();

 private:
  TempDir dir_;
  ServerOptions options_;
  std::unique_ptr<GeodexServer> server_;
};

v1::SurfacePoints ToProto(std::span<const mesh::SurfacePoint> points);
v1::ModelRef Ref(const std::string& name, int64_t version = 0);
// Batch `id` of a stream of random pairs on model "sphere" (`faces` faces):
// `pairs` pairs, the points seeded `seed` and `seed` + `b_offset`.
v1::DistanceBatch RandomSphereBatch(uint64_t id, int32_t faces, int pairs, int seed, int b_offset);
// A client context whose deadline is `seconds` away.
std::unique_ptr<grpc::ClientContext> Context(double seconds = 30);

// A unary call through the generic stub with raw request bytes (for the
// health and reflection services, whose C++ messages are not installed).
std::pair<grpc::Status, std::string> RawUnary(const std::shared_ptr<grpc::Channel>& channel,
                                              const std::string& method,
                                              const std::string& request);

// grpc.health.v1.Health/Check: returns the ServingStatus number (1 SERVING,
// 2 NOT_SERVING) or -(grpc code) on error.
int HealthCheck(const std::shared_ptr<grpc::Channel>& channel, const std::string& service);

// Every RPC against the engine: TEST_P(RpcTest, ...) runs in-process and over
// loopback (instantiated once, in server_testing.cc, for every file that
// uses it), with lowered limits.
class RpcTest : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override;
  // A Distance call; returns the status and fills `response`.
  grpc::Status Distance(const v1::DistanceRequest& request, v1::DistanceResponse* response);
  // `pairs` random pairs on the sphere model.
  v1::DistanceRequest SphereRequest(int pairs, uint32_t seed);

  std::unique_ptr<TestServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Geodex::Stub> stub_;
  std::shared_ptr<const query::QueryEngine> sphere_;
};

}  // namespace geodex::server::testing
