#include "server/server_testing.h"

#include <chrono>

#include "absl/strings/str_format.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/generic/generic_stub.h"
#include "grpcpp/security/credentials.h"

namespace geodex::server::testing {

std::shared_ptr<const query::QueryEngine> ReferenceEngine(const std::string& bytes) {
  auto index = index::Index::FromBytes(bytes);
  EXPECT_TRUE(index.ok()) << index.status();
  auto engine = query::QueryEngine::Create(*index);
  EXPECT_TRUE(engine.ok()) << engine.status();
  return *engine;
}

ServerOptions DefaultOptions(const std::string& models) {
  ServerOptions options;
  options.models_dir = models;
  options.listen = "127.0.0.1:0";
  options.workers = 2;
  options.poll_interval = absl::ZeroDuration();  // tests rescan explicitly
  return options;
}

TestServer::TestServer(std::function<void(ServerOptions&)> configure, bool write_models) {
  if (write_models) {
    WriteModelVersion(dir_.path(), "sphere", 1, SphereIndexBytes());
    WriteModelVersion(dir_.path(), "torus", 1, TorusIndexBytes());
  }
  options_ = DefaultOptions(dir_.path());
  if (configure) configure(options_);
  auto server = GeodexServer::Start(options_);
  EXPECT_TRUE(server.ok()) << server.status();
  if (!server.ok()) return;
  server_ = *std::move(server);
  server_->registry().RescanNow();
}

std::string TestServer::address() const { return absl::StrFormat("127.0.0.1:%d", server_->port()); }

std::shared_ptr<grpc::Channel> TestServer::TcpChannel() {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  return grpc::CreateCustomChannel(address(), grpc::InsecureChannelCredentials(), args);
}

void TestServer::Rescan() { server_->registry().RescanNow(); }

v1::SurfacePoints ToProto(std::span<const mesh::SurfacePoint> points) {
  v1::SurfacePoints proto;
  PointsToProto(points, &proto);
  return proto;
}

v1::DistanceBatch RandomSphereBatch(uint64_t id, int32_t faces, int pairs, int seed, int b_offset) {
  v1::DistanceBatch batch;
  batch.set_batch_id(id);
  *batch.mutable_model() = Ref("sphere");
  *batch.mutable_a() = ToProto(RandomPoints(faces, pairs, seed));
  *batch.mutable_b() = ToProto(RandomPoints(faces, pairs, seed + b_offset));
  return batch;
}

v1::ModelRef Ref(const std::string& name, int64_t version) {
  v1::ModelRef ref;
  ref.set_name(name);
  ref.set_version(version);
  return ref;
}

std::unique_ptr<grpc::ClientContext> Context(double seconds) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() +
                        std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000)));
  return context;
}

std::pair<grpc::Status, std::string> RawUnary(const std::shared_ptr<grpc::Channel>& channel,
                                              const std::string& method,
                                              const std::string& request) {
  grpc::GenericStub stub(channel);
  grpc::CompletionQueue cq;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  grpc::Slice slice(request);
  grpc::ByteBuffer request_buffer(&slice, 1), response_buffer;
  auto call = stub.PrepareUnaryCall(&context, method, request_buffer, &cq);
  call->StartCall();
  grpc::Status status;
  call->Finish(&response_buffer, &status, reinterpret_cast<void*>(1));
  void* tag;
  bool ok;
  EXPECT_TRUE(cq.Next(&tag, &ok));
  std::string bytes;
  std::vector<grpc::Slice> slices;
  if (status.ok() && response_buffer.Dump(&slices).ok()) {
    for (const grpc::Slice& s : slices)
      bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  }
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
  return {status, bytes};
}

int HealthCheck(const std::shared_ptr<grpc::Channel>& channel, const std::string& service) {
  std::string request;
  if (!service.empty()) {
    request.push_back(0x0a);  // field 1, length-delimited
    request.push_back(static_cast<char>(service.size()));
    request += service;
  }
  auto [status, response] = RawUnary(channel, "/grpc.health.v1.Health/Check", request);
  if (!status.ok()) return -static_cast<int>(status.error_code());
  if (response.empty()) return 0;  // UNKNOWN (default value omitted)
  return response.size() == 2 && response[0] == 0x08 ? response[1] : -100;
}

void RpcTest::SetUp() {
  server_ = std::make_unique<TestServer>([](ServerOptions& o) {
    o.limits.max_pairs_per_message = 5000;
    o.limits.max_matrix_cells = 100000;
    o.limits.max_field_sources = 16;
    o.limits.max_field_vertices = 300;
    o.limits.max_path_pairs = 50;
    o.limits.max_locate_positions = 100;
    o.limits.max_message_bytes = 1 << 20;
  });
  channel_ = std::string(GetParam()) == "inprocess" ? server_->server().InProcessChannel()
                                                    : server_->TcpChannel();
  stub_ = v1::Geodex::NewStub(channel_);
  sphere_ = ReferenceEngine(SphereIndexBytes());
}

grpc::Status RpcTest::Distance(const v1::DistanceRequest& request, v1::DistanceResponse* response) {
  auto context = Context();
  return stub_->Distance(context.get(), request, response);
}

v1::DistanceRequest RpcTest::SphereRequest(int pairs, uint32_t seed) {
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  const int32_t faces = sphere_->index().num_faces();
  *request.mutable_a() = ToProto(RandomPoints(faces, pairs, seed));
  *request.mutable_b() = ToProto(RandomPoints(faces, pairs, seed + 1000));
  return request;
}

INSTANTIATE_TEST_SUITE_P(Transports, RpcTest, ::testing::Values("inprocess", "loopback"),
                         [](const auto& info) { return std::string(info.param); });

}  // namespace geodex::server::testing
