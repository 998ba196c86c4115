// End-to-end tests of geodex-server: a real GeodexServer over a temporary
// model repository, called through the generated gRPC stub, both in-process
// and over a loopback TCP port. Answers are compared with the core engine on
// the same index bytes.

#include "server/server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <latch>
#include <limits>
#include <map>
#include <set>
#include <thread>

#include "absl/strings/str_format.h"
#include "core/mesh/generators.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "gmock/gmock.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/generic/generic_stub.h"
#include "grpcpp/security/credentials.h"
#include "gtest/gtest.h"
#include "server/test_util.h"

namespace geodex::server {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
namespace fs = std::filesystem;

// --- fixtures -----------------------------------------------------------------------

// A second valid sphere index (other sample count): "version 2" of a model.
const std::string& OtherSphereBytes() {
  static const std::string* bytes =
      new std::string(testing::BuildIndexBytes(mesh::gen::Sphere(3, 1.0), 30));
  return *bytes;
}

// A mesh too big for one GetMesh chunk that still builds in a moment: the
// Sphere(3) index's surface plus `kExtraVertices` unreferenced vertices (which
// the builder carries along but never propagates over).
constexpr int kExtraVertices = 400'000;
const std::string& WideSphereBytes() {
  static const std::string* bytes = [] {
    const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
    std::vector<mesh::Vec3> positions = sphere.positions();
    for (int i = 0; i < kExtraVertices; ++i) positions.emplace_back(2 + 1e-5 * i, 0.5, -0.25);
    auto wide = mesh::Mesh::Create(std::move(positions), sphere.faces(), "wide sphere");
    EXPECT_TRUE(wide.ok()) << wide.status();
    return new std::string(testing::BuildIndexBytes(*wide, 40));
  }();
  return *bytes;
}

std::shared_ptr<const query::QueryEngine> ReferenceEngine(
    const std::string& bytes, query::NearPairs near_pairs = query::NearPairs::kPath) {
  auto index = index::Index::FromBytes(bytes);
  EXPECT_TRUE(index.ok()) << index.status();
  query::QueryOptions options;
  options.near_pairs = near_pairs;
  auto engine = query::QueryEngine::Create(*index, options);
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

// A server over a repository holding "sphere" (v1) and "torus" (v1).
class TestServer {
 public:
  explicit TestServer(std::function<void(ServerOptions&)> configure = nullptr,
                      bool write_models = true) {
    if (write_models) {
      testing::WriteModelVersion(dir_.path(), "sphere", 1, testing::SphereIndexBytes());
      testing::WriteModelVersion(dir_.path(), "torus", 1, testing::TorusIndexBytes());
    }
    options_ = DefaultOptions(dir_.path());
    if (configure) configure(options_);
    auto server = GeodexServer::Start(options_);
    EXPECT_TRUE(server.ok()) << server.status();
    if (!server.ok()) return;
    server_ = *std::move(server);
    server_->registry().RescanNow();
  }
  GeodexServer& server() { return *server_; }
  const std::string& root() const { return dir_.path(); }
  std::string address() const { return absl::StrFormat("127.0.0.1:%d", server_->port()); }
  std::shared_ptr<grpc::Channel> TcpChannel() {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);
    return grpc::CreateCustomChannel(address(), grpc::InsecureChannelCredentials(), args);
  }
  void Rescan() { server_->registry().RescanNow(); }

 private:
  testing::TempDir dir_;
  ServerOptions options_;
  std::unique_ptr<GeodexServer> server_;
};

// Reads a GetMesh stream to its end.
struct MeshReply {
  grpc::Status status;
  std::vector<v1::MeshChunk> chunks;
};
MeshReply ReadMesh(v1::Geodex::Stub& stub, const v1::ModelRef& model) {
  v1::GetMeshRequest request;
  *request.mutable_model() = model;
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto reader = stub.GetMesh(context.get(), request);
  MeshReply reply;
  v1::MeshChunk chunk;
  while (reader->Read(&chunk)) reply.chunks.push_back(chunk);
  reply.status = reader->Finish();
  return reply;
}

// Expects `chunks` to tile `ix`'s mesh in order, each with the totals and
// `version`, at most `per_chunk` vertices and faces each, and the positions
// and faces to be exactly the index's.
void ExpectMeshOfIndex(const std::vector<v1::MeshChunk>& chunks, const index::Index& ix,
                       int64_t version, int per_chunk = 1 << 16) {
  std::vector<double> positions;
  std::vector<int32_t> faces;
  for (const v1::MeshChunk& chunk : chunks) {
    EXPECT_EQ(chunk.num_vertices(), static_cast<uint32_t>(ix.num_vertices()));
    EXPECT_EQ(chunk.num_faces(), static_cast<uint32_t>(ix.num_faces()));
    EXPECT_EQ(chunk.version(), version);
    EXPECT_EQ(chunk.vertex_offset(), positions.size() / 3);
    EXPECT_EQ(chunk.face_offset(), faces.size() / 3);
    EXPECT_LE(chunk.positions_size(), 3 * per_chunk);
    EXPECT_LE(chunk.faces_size(), 3 * per_chunk);
    EXPECT_LT(chunk.ByteSizeLong(), 5u << 19);  // 2.5 MiB
    ASSERT_EQ(chunk.positions_size() % 3, 0);
    ASSERT_EQ(chunk.faces_size() % 3, 0);
    positions.insert(positions.end(), chunk.positions().begin(), chunk.positions().end());
    faces.insert(faces.end(), chunk.faces().begin(), chunk.faces().end());
  }
  EXPECT_TRUE(
      std::equal(positions.begin(), positions.end(), ix.positions().begin(), ix.positions().end()));
  EXPECT_TRUE(std::equal(faces.begin(), faces.end(), ix.faces().begin(), ix.faces().end()));
}

v1::SurfacePoints ToProto(std::span<const mesh::SurfacePoint> points) {
  v1::SurfacePoints proto;
  testing::PointsToProto(points, &proto);
  return proto;
}

v1::ModelRef Ref(const std::string& name, int64_t version = 0) {
  v1::ModelRef ref;
  ref.set_name(name);
  ref.set_version(version);
  return ref;
}

std::unique_ptr<grpc::ClientContext> Context(double seconds = 30) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() +
                        std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000)));
  return context;
}

// A unary call through the generic stub with raw request bytes (for the
// health and reflection services, whose C++ messages are not installed).
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

// grpc.health.v1.Health/Check: returns the ServingStatus number (1 SERVING,
// 2 NOT_SERVING) or -(grpc code) on error.
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

// GET /metrics over a plain socket.
std::string HttpGet(int port, const std::string& path) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    close(fd);
    return "";
  }
  const std::string request =
      "GET " + path + " HTTP/1.0\r\nHost: localhost\r\nConnection: close\r\n\r\n";
  (void)!write(fd, request.data(), request.size());
  shutdown(fd, SHUT_WR);  // no more requests on this connection
  std::string response;
  char buffer[4096];
  ssize_t n;
  while ((n = read(fd, buffer, sizeof(buffer))) > 0) response.append(buffer, n);
  close(fd);
  return response;
}

// --- every RPC against the engine, in-process and over loopback -----------------------

class RpcTest : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override {
    server_ = std::make_unique<TestServer>([](ServerOptions& o) {
      o.limits.max_pairs_per_message = 5000;
      o.limits.max_matrix_cells = 100000;
      o.limits.max_field_sources = 16;
      o.limits.max_path_pairs = 50;
      o.limits.max_locate_positions = 100;
      o.limits.max_message_bytes = 1 << 20;
    });
    channel_ = std::string(GetParam()) == "inprocess" ? server_->server().InProcessChannel()
                                                      : server_->TcpChannel();
    stub_ = v1::Geodex::NewStub(channel_);
    sphere_ = ReferenceEngine(testing::SphereIndexBytes());
  }
  // A Distance call; returns the status and fills `response`.
  grpc::Status Distance(const v1::DistanceRequest& request, v1::DistanceResponse* response) {
    auto context = Context();
    return stub_->Distance(context.get(), request, response);
  }
  v1::DistanceRequest SphereRequest(int pairs, uint32_t seed) {
    v1::DistanceRequest request;
    *request.mutable_model() = Ref("sphere");
    const int32_t faces = sphere_->index().num_faces();
    *request.mutable_a() = ToProto(testing::RandomPoints(faces, pairs, seed));
    *request.mutable_b() = ToProto(testing::RandomPoints(faces, pairs, seed + 1000));
    return request;
  }

  std::unique_ptr<TestServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Geodex::Stub> stub_;
  std::shared_ptr<const query::QueryEngine> sphere_;
};

TEST_P(RpcTest, ListModelsAndGetModel) {
  v1::ListModelsResponse list;
  auto context = Context();
  ASSERT_TRUE(stub_->ListModels(context.get(), {}, &list).ok());
  ASSERT_EQ(list.models_size(), 2);
  EXPECT_EQ(list.models(0).name(), "sphere");
  EXPECT_EQ(list.models(1).name(), "torus");
  for (const v1::ModelInfo& m : list.models()) {
    EXPECT_EQ(m.state(), v1::ModelInfo::SERVING);
    EXPECT_EQ(m.version(), 1);
  }
  v1::GetModelRequest get;
  *get.mutable_model() = Ref("sphere");
  v1::ModelInfo info;
  context = Context();
  ASSERT_TRUE(stub_->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.num_vertices(), sphere_->index().num_vertices());
  EXPECT_EQ(info.num_faces(), sphere_->index().num_faces());
  EXPECT_EQ(info.num_samples(), sphere_->index().num_samples());
  EXPECT_EQ(info.mapped_bytes(), static_cast<int64_t>(testing::SphereIndexBytes().size()));
  EXPECT_EQ(info.available_versions_size(), 1);
  EXPECT_FALSE(info.build_report().empty());

  *get.mutable_model() = Ref("nope");
  context = Context();
  grpc::Status s = stub_->GetModel(context.get(), get, &info);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(s.error_message(), HasSubstr("unknown model 'nope'"));
  *get.mutable_model() = Ref("../sphere");
  context = Context();
  EXPECT_EQ(stub_->GetModel(context.get(), get, &info).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  *get.mutable_model() = Ref("sphere", 9);
  context = Context();
  EXPECT_EQ(stub_->GetModel(context.get(), get, &info).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_P(RpcTest, DistanceMatchesTheEngine) {
  const v1::DistanceRequest request = SphereRequest(500, 1);
  v1::DistanceResponse response;
  ASSERT_TRUE(Distance(request, &response).ok());
  ASSERT_EQ(response.distances_size(), 500);
  EXPECT_EQ(response.version(), 1);
  const int32_t faces = sphere_->index().num_faces();
  auto a = testing::RandomPoints(faces, 500, 1), b = testing::RandomPoints(faces, 500, 1001);
  for (int i = 0; i < 500; ++i) {
    auto d = sphere_->Distance(a[i], b[i]);
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(response.distances(i), *d) << i;
  }
}

TEST_P(RpcTest, ExactNearPairsMatchTheExactEngine) {
  auto exact = ReferenceEngine(testing::SphereIndexBytes(), query::NearPairs::kExact);
  // Near pairs: b is a's point nudged within the same face.
  const int32_t faces = sphere_->index().num_faces();
  auto a = testing::RandomPoints(faces, 50, 7);
  auto b = a;
  for (auto& p : b) p.w = {p.w[0] * 0.5 + 0.5 / 3, p.w[1] * 0.5 + 0.5 / 3, p.w[2] * 0.5 + 0.5 / 3};
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  request.set_exact_near_pairs(true);
  v1::DistanceResponse response;
  ASSERT_TRUE(Distance(request, &response).ok());
  query::QueryScratch scratch;
  std::vector<double> expected(a.size());
  ASSERT_TRUE(exact->DistanceBatch(a, b, expected, &scratch).ok());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(response.distances(i), expected[i]) << i;
}

TEST_P(RpcTest, StreamDistancesAnswersEveryBatchInOrder) {
  auto context = Context();
  auto stream = stub_->StreamDistances(context.get());
  const int32_t faces = sphere_->index().num_faces();
  constexpr int kBatches = 30;
  // A bidirectional stream must be read while it is written: the server reads
  // only a few batches ahead of the answers the client has taken.
  std::thread writer([&] {
    for (int k = 0; k < kBatches; ++k) {
      v1::DistanceBatch batch;
      batch.set_batch_id(100 + k);
      if (k == 0) *batch.mutable_model() = Ref("sphere");
      *batch.mutable_a() = ToProto(testing::RandomPoints(faces, 100, k));
      *batch.mutable_b() = ToProto(testing::RandomPoints(faces, 100, k + 500));
      if (k == 7) batch.mutable_a()->set_faces(3, 1 << 30);  // a bad batch: answered, not fatal
      if (!stream->Write(batch)) break;
    }
    stream->WritesDone();
  });
  v1::DistanceResult result;
  for (int k = 0; k < kBatches; ++k) {
    ASSERT_TRUE(stream->Read(&result)) << k;
    EXPECT_EQ(result.batch_id(), 100u + k);
    if (k == 7) {
      EXPECT_EQ(result.error_code(), static_cast<int>(grpc::StatusCode::OUT_OF_RANGE));
      EXPECT_THAT(result.error_message(), StartsWith("a[3]: face id 1073741824 out of range"));
      EXPECT_EQ(result.distances_size(), 0);
      continue;
    }
    ASSERT_EQ(result.error_code(), 0) << result.error_message();
    EXPECT_EQ(result.version(), 1);
    auto a = testing::RandomPoints(faces, 100, k), b = testing::RandomPoints(faces, 100, k + 500);
    std::vector<double> expected(100);
    ASSERT_TRUE(sphere_->DistanceBatch(a, b, expected).ok());
    ASSERT_EQ(result.distances_size(), 100);
    for (int i = 0; i < 100; ++i) EXPECT_EQ(result.distances(i), expected[i]);
  }
  EXPECT_FALSE(stream->Read(&result));
  writer.join();
  EXPECT_TRUE(stream->Finish().ok());
}

TEST_P(RpcTest, StreamWithoutAModelGetsAnErrorPerBatch) {
  auto context = Context();
  auto stream = stub_->StreamDistances(context.get());
  v1::DistanceBatch batch;
  batch.set_batch_id(1);
  *batch.mutable_a() = ToProto(testing::RandomPoints(10, 1, 1));
  *batch.mutable_b() = ToProto(testing::RandomPoints(10, 1, 2));
  ASSERT_TRUE(stream->Write(batch));
  batch.set_batch_id(2);
  *batch.mutable_model() = Ref("missing");
  ASSERT_TRUE(stream->Write(batch));
  stream->WritesDone();
  v1::DistanceResult result;
  ASSERT_TRUE(stream->Read(&result));
  EXPECT_EQ(result.error_code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_THAT(result.error_message(), HasSubstr("names no model"));
  ASSERT_TRUE(stream->Read(&result));
  EXPECT_EQ(result.error_code(), static_cast<int>(grpc::StatusCode::NOT_FOUND));
  EXPECT_TRUE(stream->Finish().ok());
}

TEST_P(RpcTest, MatrixMatchesTheEngineInBlocks) {
  const int32_t faces = sphere_->index().num_faces();
  auto sources = testing::RandomPoints(faces, 23, 3), targets = testing::RandomPoints(faces, 40, 4);
  for (int block_rows : {0, 5}) {
    v1::MatrixRequest request;
    *request.mutable_model() = Ref("sphere");
    *request.mutable_sources() = ToProto(sources);
    *request.mutable_targets() = ToProto(targets);
    request.set_block_rows(block_rows);
    auto context = Context();
    auto reader = stub_->Matrix(context.get(), request);
    v1::MatrixBlock block;
    int64_t next_row = 0;
    int blocks = 0;
    while (reader->Read(&block)) {
      ++blocks;
      EXPECT_EQ(block.row_offset(), next_row);
      EXPECT_EQ(block.num_targets(), 40);
      ASSERT_EQ(block.values_size(), block.rows() * 40);
      for (int64_t r = 0; r < block.rows(); ++r) {
        for (int t = 0; t < 40; ++t) {
          EXPECT_EQ(block.values(r * 40 + t),
                    *sphere_->Distance(sources[next_row + r], targets[t]));
        }
      }
      next_row += block.rows();
    }
    ASSERT_TRUE(reader->Finish().ok());
    EXPECT_EQ(next_row, 23);
    EXPECT_EQ(blocks, block_rows == 5 ? 5 : 1);
  }
}

TEST_P(RpcTest, PathMatchesTheEngine) {
  const int32_t faces = sphere_->index().num_faces();
  auto a = testing::RandomPoints(faces, 5, 11), b = testing::RandomPoints(faces, 5, 12);
  v1::PathRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  v1::PathResponse response;
  auto context = Context();
  ASSERT_TRUE(stub_->Path(context.get(), request, &response).ok());
  ASSERT_EQ(response.paths_size(), 5);
  for (int i = 0; i < 5; ++i) {
    auto path = sphere_->Path(a[i], b[i]);
    ASSERT_TRUE(path.ok());
    const v1::Polyline& line = response.paths(i);
    ASSERT_EQ(line.points().faces_size(), static_cast<int>(path->size()));
    double length = 0;
    for (size_t k = 0; k < path->size(); ++k) {
      EXPECT_EQ(line.points().faces(k), (*path)[k].point.face);
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(line.positions().xyz(3 * k + c), (*path)[k].position[c]);
      if (k > 0) length += ((*path)[k].position - (*path)[k - 1].position).norm();
    }
    EXPECT_DOUBLE_EQ(line.length(), length);
    // The path is about as long as the distance.
    EXPECT_NEAR(line.length(), *sphere_->Distance(a[i], b[i]), 0.1);
  }
}

TEST_P(RpcTest, PathWithAnExactCorridorMatchesTheEngine) {
  const int32_t faces = sphere_->index().num_faces();
  auto a = testing::RandomPoints(faces, 4, 13), b = testing::RandomPoints(faces, 4, 14);
  v1::PathRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  request.set_exact_corridor(6);
  v1::PathResponse response;
  auto context = Context();
  ASSERT_TRUE(stub_->Path(context.get(), request, &response).ok());
  ASSERT_EQ(response.paths_size(), 4);
  for (int i = 0; i < 4; ++i) {
    auto path = sphere_->Path(a[i], b[i], 6);
    ASSERT_TRUE(path.ok());
    const v1::Polyline& line = response.paths(i);
    ASSERT_EQ(line.points().faces_size(), static_cast<int>(path->size()));
    for (size_t k = 0; k < path->size(); ++k) {
      EXPECT_EQ(line.points().faces(k), (*path)[k].point.face);
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(line.positions().xyz(3 * k + c), (*path)[k].position[c]);
    }
    // No longer than the traced path.
    auto traced = sphere_->Path(a[i], b[i]);
    ASSERT_TRUE(traced.ok());
    double traced_length = 0;
    for (size_t k = 1; k < traced->size(); ++k)
      traced_length += ((*traced)[k].position - (*traced)[k - 1].position).norm();
    EXPECT_LE(line.length(), traced_length * (1 + 1e-12));
  }
  request.set_exact_corridor(65);
  context = Context();
  grpc::Status s = stub_->Path(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("exact_corridor"));
}

TEST_P(RpcTest, DistanceFieldMatchesTheEngine) {
  const int32_t faces = sphere_->index().num_faces();
  auto sources = testing::RandomPoints(faces, 3, 21);
  v1::DistanceFieldRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_sources() = ToProto(sources);
  request.set_with_nearest_source(true);
  auto context = Context();
  auto reader = stub_->DistanceField(context.get(), request);
  auto field = sphere_->Field(sources);
  ASSERT_TRUE(field.ok());
  v1::DistanceFieldChunk chunk;
  int64_t next = 0;
  while (reader->Read(&chunk)) {
    EXPECT_EQ(chunk.vertex_offset(), next);
    EXPECT_EQ(chunk.num_vertices(), sphere_->index().num_vertices());
    EXPECT_LE(chunk.ByteSizeLong(), (1u << 20) + 64);
    ASSERT_EQ(chunk.nearest_source_size(), chunk.distances_size());
    for (int i = 0; i < chunk.distances_size(); ++i) {
      EXPECT_EQ(chunk.distances(i), field->distance[next + i]);
      EXPECT_EQ(chunk.nearest_source(i), field->nearest[next + i]);
    }
    next += chunk.distances_size();
  }
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_EQ(next, sphere_->index().num_vertices());
}

TEST_P(RpcTest, GetMeshIsTheIndexMesh) {
  const MeshReply reply = ReadMesh(*stub_, Ref("sphere"));
  ASSERT_TRUE(reply.status.ok()) << reply.status.error_message();
  ASSERT_EQ(reply.chunks.size(), 1u);  // 642 vertices, 1280 faces
  EXPECT_EQ(reply.chunks[0].num_vertices(), 642u);
  EXPECT_EQ(reply.chunks[0].num_faces(), 1280u);
  ExpectMeshOfIndex(reply.chunks, sphere_->index(), 1);

  const MeshReply pinned = ReadMesh(*stub_, Ref("torus", 1));
  ASSERT_TRUE(pinned.status.ok()) << pinned.status.error_message();
  ExpectMeshOfIndex(pinned.chunks, ReferenceEngine(testing::TorusIndexBytes())->index(), 1);
}

TEST_P(RpcTest, GetMeshOfAnUnknownModelOrVersionIsNotFound) {
  MeshReply reply = ReadMesh(*stub_, Ref("nope"));
  EXPECT_EQ(reply.status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(reply.status.error_message(), HasSubstr("nope"));
  EXPECT_TRUE(reply.chunks.empty());
  reply = ReadMesh(*stub_, Ref("sphere", 9));
  EXPECT_EQ(reply.status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_TRUE(reply.chunks.empty());
  reply = ReadMesh(*stub_, Ref("../sphere"));
  EXPECT_EQ(reply.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_P(RpcTest, LocateMatchesTheEngine) {
  v1::LocateRequest request;
  *request.mutable_model() = Ref("sphere");
  const std::vector<mesh::Vec3> xs = {{0, 0, 2}, {0.3, -0.2, 0.1}, {1, 1, 1}};
  for (const auto& x : xs) {
    for (int c = 0; c < 3; ++c) request.mutable_positions()->add_xyz(x[c]);
  }
  v1::LocateResponse response;
  auto context = Context();
  ASSERT_TRUE(stub_->Locate(context.get(), request, &response).ok());
  ASSERT_EQ(response.distances_size(), 3);
  for (int i = 0; i < 3; ++i) {
    auto located = sphere_->Locate(xs[i]);
    ASSERT_TRUE(located.ok());
    EXPECT_EQ(response.points().faces(i), located->point.face);
    EXPECT_EQ(response.distances(i), located->distance);
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(response.points().weights(3 * i + c), located->point.w[c]);
  }
  request.mutable_positions()->set_xyz(4, std::numeric_limits<double>::infinity());
  context = Context();
  grpc::Status s = stub_->Locate(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), StartsWith("positions[1]: y is inf"));
}

// --- every invalid-input class ------------------------------------------------------

TEST_P(RpcTest, InvalidPointsAreRejectedNamingTheElement) {
  const int32_t faces = sphere_->index().num_faces();
  struct Case {
    const char* what;
    std::function<void(v1::DistanceRequest&)> corrupt;
    grpc::StatusCode code;
    std::string message;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<Case> cases = {
      {"face out of range", [](auto& r) { r.mutable_a()->set_faces(17, 99999); },
       grpc::StatusCode::OUT_OF_RANGE,
       absl::StrFormat("a[17]: face id 99999 out of range [0, %d)", faces)},
      {"negative face", [](auto& r) { r.mutable_b()->set_faces(2, -3); },
       grpc::StatusCode::OUT_OF_RANGE, "b[2]: face id -3 out of range"},
      {"NaN weight", [&](auto& r) { r.mutable_b()->set_weights(3 * 4 + 1, nan); },
       grpc::StatusCode::INVALID_ARGUMENT, "b[4]: barycentric weight 1"},
      {"Inf weight", [&](auto& r) { r.mutable_a()->set_weights(0, inf); },
       grpc::StatusCode::INVALID_ARGUMENT, "a[0]: barycentric weight 0"},
      {"negative weight",
       [](auto& r) {
         r.mutable_a()->set_weights(3 * 5, 1.5);
         r.mutable_a()->set_weights(3 * 5 + 1, -0.5);
         r.mutable_a()->set_weights(3 * 5 + 2, 0);
       },
       grpc::StatusCode::INVALID_ARGUMENT, "a[5]: barycentric weight 1 of face"},
      {"weights not summing to 1", [](auto& r) { r.mutable_b()->set_weights(3 * 9, 0.9); },
       grpc::StatusCode::INVALID_ARGUMENT, "b[9]: barycentric weights of face"},
      {"mismatched lengths",
       [](auto& r) {
         r.mutable_b()->mutable_faces()->RemoveLast();
         for (int k = 0; k < 3; ++k) r.mutable_b()->mutable_weights()->RemoveLast();
       },
       grpc::StatusCode::INVALID_ARGUMENT, "a has 20 points but b has 19"},
      {"weights not 3 per face", [](auto& r) { r.mutable_a()->mutable_weights()->RemoveLast(); },
       grpc::StatusCode::INVALID_ARGUMENT, "a: 20 faces but 59 weights (want 60)"},
      {"unknown model", [](auto& r) { *r.mutable_model() = Ref("bunny"); },
       grpc::StatusCode::NOT_FOUND, "unknown model 'bunny'"},
      {"escaping model name", [](auto& r) { *r.mutable_model() = Ref("../../etc"); },
       grpc::StatusCode::INVALID_ARGUMENT, "model name '../../etc'"},
      {"unserved version", [](auto& r) { *r.mutable_model() = Ref("sphere", 3); },
       grpc::StatusCode::NOT_FOUND, "model 'sphere' has no served version 3"},
  };
  for (const Case& c : cases) {
    v1::DistanceRequest request = SphereRequest(20, 5);
    c.corrupt(request);
    v1::DistanceResponse response;
    grpc::Status s = Distance(request, &response);
    EXPECT_EQ(s.error_code(), c.code) << c.what << ": " << s.error_message();
    EXPECT_THAT(s.error_message(), StartsWith(c.message)) << c.what;
  }
}

TEST_P(RpcTest, OversizedRequestsAreResourceExhausted) {
  v1::DistanceResponse response;
  grpc::Status s = Distance(SphereRequest(5001, 1), &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("5001 pairs exceed the limit of 5000"));
  EXPECT_TRUE(Distance(SphereRequest(5000, 1), &response).ok());

  const int32_t faces = sphere_->index().num_faces();
  {  // matrix cells: 400 x 300 > 100000
    v1::MatrixRequest request;
    *request.mutable_model() = Ref("sphere");
    *request.mutable_sources() = ToProto(testing::RandomPoints(faces, 400, 1));
    *request.mutable_targets() = ToProto(testing::RandomPoints(faces, 300, 2));
    auto context = Context();
    auto reader = stub_->Matrix(context.get(), request);
    v1::MatrixBlock block;
    EXPECT_FALSE(reader->Read(&block));
    s = reader->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(s.error_message(), HasSubstr("max_matrix_cells"));
  }
  {  // field sources
    v1::DistanceFieldRequest request;
    *request.mutable_model() = Ref("sphere");
    *request.mutable_sources() = ToProto(testing::RandomPoints(faces, 17, 1));
    auto context = Context();
    auto reader = stub_->DistanceField(context.get(), request);
    v1::DistanceFieldChunk chunk;
    EXPECT_FALSE(reader->Read(&chunk));
    s = reader->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(s.error_message(), HasSubstr("max_field_sources"));
  }
  {  // path pairs
    v1::PathRequest request;
    *request.mutable_model() = Ref("sphere");
    *request.mutable_a() = ToProto(testing::RandomPoints(faces, 51, 1));
    *request.mutable_b() = ToProto(testing::RandomPoints(faces, 51, 2));
    v1::PathResponse response;
    auto context = Context();
    s = stub_->Path(context.get(), request, &response);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(s.error_message(), HasSubstr("max_path_pairs"));
  }
  {  // locate positions
    v1::LocateRequest request;
    *request.mutable_model() = Ref("sphere");
    for (int i = 0; i < 303; ++i) request.mutable_positions()->add_xyz(0.1);
    v1::LocateResponse response;
    auto context = Context();
    s = stub_->Locate(context.get(), request, &response);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(s.error_message(), HasSubstr("max_locate_positions"));
  }
  if (std::string(GetParam()) == "loopback") {  // message size (enforced by the transport)
    v1::DistanceRequest request = SphereRequest(10, 1);
    for (int i = 0; i < (1 << 20) / 8 + 10; ++i) request.mutable_a()->add_weights(0);
    s = Distance(request, &response);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << s.error_message();
  }
}

INSTANTIATE_TEST_SUITE_P(Transports, RpcTest, ::testing::Values("inprocess", "loopback"),
                         [](const auto& info) { return std::string(info.param); });

// --- limits, deadlines, cancellation, overload (loopback) ------------------------------

TEST(ServerTest, PerModelConfigLowersLimitsAndForcesExactNearPairs) {
  TestServer ts;
  testing::WriteModelConfig(ts.root(), "sphere",
                            "exact_near_pairs: true\nlimits { max_pairs_per_message: 10 }\n");
  ts.Rescan();
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto exact = ReferenceEngine(testing::SphereIndexBytes(), query::NearPairs::kExact);
  const int32_t faces = exact->index().num_faces();
  auto a = testing::RandomPoints(faces, 10, 3);
  auto b = a;
  for (auto& p : b) p.w = {1.0 / 3, 1.0 / 3, 1.0 / 3};
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  v1::DistanceResponse response;
  auto context = Context();
  ASSERT_TRUE(stub->Distance(context.get(), request, &response).ok());
  query::QueryScratch scratch;
  std::vector<double> expected(10);
  ASSERT_TRUE(exact->DistanceBatch(a, b, expected, &scratch).ok());
  for (int i = 0; i < 10; ++i) EXPECT_EQ(response.distances(i), expected[i]);

  *request.mutable_a() = ToProto(testing::RandomPoints(faces, 11, 3));
  *request.mutable_b() = ToProto(testing::RandomPoints(faces, 11, 4));
  context = Context();
  grpc::Status s = stub->Distance(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("limit of 10"));
}

TEST(ServerTest, NearPairsByPathLengthUnlessTheModelAsksForThePureO1Mode) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto by_path = ReferenceEngine(testing::SphereIndexBytes());
  auto unfold = ReferenceEngine(testing::SphereIndexBytes(), query::NearPairs::kUnfold);
  const int32_t faces = by_path->index().num_faces();
  // Near pairs: a point and another of the same face.
  const auto a = testing::RandomPoints(faces, 40, 5);
  auto b = testing::RandomPoints(faces, 40, 6);
  for (size_t i = 0; i < b.size(); ++i) b[i].face = a[i].face;
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  auto answers = [&] {
    v1::DistanceResponse response;
    auto context = Context();
    EXPECT_TRUE(stub->Distance(context.get(), request, &response).ok());
    return std::vector<double>(response.distances().begin(), response.distances().end());
  };
  std::vector<double> expected_path(a.size()), expected_unfold(a.size());
  ASSERT_TRUE(by_path->DistanceBatch(a, b, expected_path).ok());
  ASSERT_TRUE(unfold->DistanceBatch(a, b, expected_unfold).ok());
  ASSERT_NE(expected_path, expected_unfold);
  EXPECT_EQ(answers(), expected_path);
  testing::WriteModelConfig(ts.root(), "sphere", "unfold_near_pairs: true\n");
  ts.Rescan();
  EXPECT_EQ(answers(), expected_unfold);
  // A request's own mode wins over the model's.
  request.set_near_pairs(v1::NEAR_PAIRS_PATH);
  EXPECT_EQ(answers(), expected_path);
}

TEST(ServerTest, EachRequestMayChooseItsNearPairMode) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  query::QueryScratch scratch;
  const int32_t faces = ReferenceEngine(testing::SphereIndexBytes())->index().num_faces();
  const auto a = testing::RandomPoints(faces, 40, 5);
  auto b = testing::RandomPoints(faces, 40, 6);
  for (size_t i = 0; i < b.size(); ++i) b[i].face = a[i].face;  // near pairs
  std::map<v1::NearPairs, std::vector<double>> expected;
  for (auto [wire, mode] : {std::pair{v1::NEAR_PAIRS_PATH, query::NearPairs::kPath},
                            std::pair{v1::NEAR_PAIRS_UNFOLD, query::NearPairs::kUnfold},
                            std::pair{v1::NEAR_PAIRS_EXACT, query::NearPairs::kExact}}) {
    auto engine = ReferenceEngine(testing::SphereIndexBytes(), mode);
    expected[wire].resize(a.size());
    ASSERT_TRUE(engine->DistanceBatch(a, b, expected[wire], &scratch).ok());
  }
  ASSERT_NE(expected[v1::NEAR_PAIRS_PATH], expected[v1::NEAR_PAIRS_UNFOLD]);
  ASSERT_NE(expected[v1::NEAR_PAIRS_PATH], expected[v1::NEAR_PAIRS_EXACT]);
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  auto call = [&](std::vector<double>* out) {
    v1::DistanceResponse response;
    auto context = Context();
    const grpc::Status status = stub->Distance(context.get(), request, &response);
    out->assign(response.distances().begin(), response.distances().end());
    return status;
  };
  std::vector<double> got;
  for (const auto& [wire, want] : expected) {
    request.set_near_pairs(wire);
    ASSERT_TRUE(call(&got).ok()) << v1::NearPairs_Name(wire);
    EXPECT_EQ(got, want) << v1::NearPairs_Name(wire);
  }
  // The deprecated flag is the exact mode, and contradicting it is an error.
  request.set_near_pairs(v1::NEAR_PAIRS_UNSPECIFIED);
  request.set_exact_near_pairs(true);
  ASSERT_TRUE(call(&got).ok());
  EXPECT_EQ(got, expected[v1::NEAR_PAIRS_EXACT]);
  request.set_near_pairs(v1::NEAR_PAIRS_UNFOLD);
  grpc::Status status = call(&got);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("contradicts near_pairs = NEAR_PAIRS_UNFOLD"));
  request.set_exact_near_pairs(false);
  request.set_near_pairs(static_cast<v1::NearPairs>(7));
  status = call(&got);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("unknown value 7"));
  // Matrix rows are DistanceBatch answers in the mode asked for.
  v1::MatrixRequest matrix;
  *matrix.mutable_model() = Ref("sphere");
  *matrix.mutable_sources() = ToProto(std::vector<mesh::SurfacePoint>{a[0]});
  *matrix.mutable_targets() = ToProto(std::vector<mesh::SurfacePoint>{b[0]});
  matrix.set_near_pairs(v1::NEAR_PAIRS_UNFOLD);
  auto context = Context();
  auto reader = stub->Matrix(context.get(), matrix);
  v1::MatrixBlock block;
  ASSERT_TRUE(reader->Read(&block));
  ASSERT_EQ(block.values_size(), 1);
  EXPECT_EQ(block.values(0), expected[v1::NEAR_PAIRS_UNFOLD][0]);
  while (reader->Read(&block)) {
  }
  EXPECT_TRUE(reader->Finish().ok());
}

TEST(ServerTest, DeadlineExpiredWhileQueuedIsNotComputed) {
  TestServer ts([](ServerOptions& o) { o.workers = 1; });
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  std::latch blocked(1), release(1);
  ASSERT_TRUE(ts.server().pool().Submit([&](WorkerContext&) {
    blocked.count_down();
    release.wait();
  }));
  blocked.wait();
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(testing::RandomPoints(100, 1, 1));
  *request.mutable_b() = ToProto(testing::RandomPoints(100, 1, 2));
  v1::DistanceResponse response;
  auto context = Context(0.2);
  EXPECT_EQ(stub->Distance(context.get(), request, &response).error_code(),
            grpc::StatusCode::DEADLINE_EXCEEDED);
  // The server's deadline (sent as a timeout) ends a little after the
  // client's; let it pass before the worker frees up.
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  release.count_down();
  // The queued job sees the expired deadline and records it.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (ts.server().metrics().Text().find(
             "geodex_requests_total{code=\"DEADLINE_EXCEEDED\",method=\"Distance\"") ==
             std::string::npos &&
         std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_THAT(ts.server().metrics().Text(),
              HasSubstr("geodex_requests_total{code=\"DEADLINE_EXCEEDED\",method=\"Distance\""));
}

TEST(ServerTest, FullWorkerQueueIsResourceExhausted) {
  TestServer ts([](ServerOptions& o) {
    o.workers = 1;
    o.queue_capacity = 1;
  });
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  std::latch blocked(1), release(1);
  ASSERT_TRUE(ts.server().pool().Submit([&](WorkerContext&) {
    blocked.count_down();
    release.wait();
  }));
  blocked.wait();
  ASSERT_TRUE(ts.server().pool().Submit([](WorkerContext&) {}));  // the queue is full
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  v1::DistanceResponse response;
  auto context = Context();
  grpc::Status s = stub->Distance(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("server busy"));
  release.count_down();
}

TEST(ServerTest, TooManyConcurrentStreamsAreResourceExhausted) {
  TestServer ts([](ServerOptions& o) { o.limits.max_concurrent_streams = 2; });
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto c1 = Context(), c2 = Context(), c3 = Context();
  auto s1 = stub->StreamDistances(c1.get());
  auto s2 = stub->StreamDistances(c2.get());
  // Both admitted once the server has seen them.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (ts.server().service().active_streams() < 2 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(ts.server().service().active_streams(), 2);
  auto s3 = stub->StreamDistances(c3.get());
  v1::DistanceResult result;
  EXPECT_FALSE(s3->Read(&result));
  grpc::Status s = s3->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("max_concurrent_streams"));
  for (auto* stream : {s1.get(), s2.get()}) {
    stream->WritesDone();
    EXPECT_TRUE(stream->Finish().ok());
  }
}

TEST(ServerTest, CancelledMatrixStopsComputing) {
  TestServer ts([](ServerOptions& o) { o.workers = 1; });
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  const int32_t faces = 1280;  // Sphere(3)
  v1::MatrixRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_sources() = ToProto(testing::RandomPoints(faces, 2000, 1));
  *request.mutable_targets() = ToProto(testing::RandomPoints(faces, 2000, 2));
  request.set_block_rows(1);
  auto context = Context();
  auto reader = stub->Matrix(context.get(), request);
  v1::MatrixBlock block;
  ASSERT_TRUE(reader->Read(&block));
  ASSERT_TRUE(reader->Read(&block));
  context->TryCancel();
  while (reader->Read(&block)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (ts.server().service().active_streams() > 0 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(ts.server().service().active_streams(), 0);
  // Far fewer than the 2000 rows were computed.
  const std::string text = ts.server().metrics().Text();
  EXPECT_THAT(text, HasSubstr("geodex_requests_total{code=\"CANCELLED\",method=\"Matrix\""));
}

TEST(ServerTest, GetMeshOfALargeMeshComesInSeveralChunks) {
  TestServer ts;
  testing::WriteModelVersion(ts.root(), "wide", 1, WideSphereBytes());
  ts.Rescan();
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  const MeshReply reply = ReadMesh(*stub, Ref("wide"));
  ASSERT_TRUE(reply.status.ok()) << reply.status.error_message();
  auto index = index::Index::FromBytes(WideSphereBytes());
  ASSERT_TRUE(index.ok()) << index.status();
  ASSERT_EQ((*index)->num_vertices(), 642 + kExtraVertices);
  // 400642 vertices in chunks of 65536; the 1280 faces all in the first.
  ASSERT_EQ(reply.chunks.size(), 7u);
  EXPECT_EQ(reply.chunks[0].faces_size(), 3 * 1280);
  EXPECT_EQ(reply.chunks[1].faces_size(), 0);
  EXPECT_EQ(reply.chunks[1].face_offset(), 1280u);
  ExpectMeshOfIndex(reply.chunks, **index, 1);
}

TEST(ServerTest, GetMeshInSmallChunksTilesVerticesAndFaces) {
  TestServer ts([](ServerOptions& o) { o.limits.mesh_chunk_elements = 100; });
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  const MeshReply reply = ReadMesh(*stub, Ref("sphere"));
  ASSERT_TRUE(reply.status.ok()) << reply.status.error_message();
  // 642 vertices: 7 chunks; 1280 faces: 13 chunks, the last 6 without vertices.
  ASSERT_EQ(reply.chunks.size(), 13u);
  EXPECT_EQ(reply.chunks[6].positions_size(), 3 * 42);
  EXPECT_EQ(reply.chunks[7].positions_size(), 0);
  EXPECT_EQ(reply.chunks[7].vertex_offset(), 642u);
  EXPECT_EQ(reply.chunks[12].faces_size(), 3 * 80);
  ExpectMeshOfIndex(reply.chunks, ReferenceEngine(testing::SphereIndexBytes())->index(), 1, 100);
  const std::string text = ts.server().metrics().Text();
  EXPECT_THAT(text, HasSubstr("geodex_requests_total{code=\"OK\",method=\"GetMesh\""));
  EXPECT_THAT(text, HasSubstr("geodex_pairs_total{method=\"GetMesh\",model=\"sphere\"} 1922"));
}

TEST(ServerTest, GetMeshKeepsItsVersionWhenTheModelIsRemovedMidStream) {
  TestServer ts([](ServerOptions& o) { o.limits.mesh_chunk_elements = 1000; });
  testing::WriteModelVersion(ts.root(), "wide", 1, WideSphereBytes());
  ts.Rescan();
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  v1::GetMeshRequest request;
  *request.mutable_model() = Ref("wide");
  auto context = Context();
  auto reader = stub->GetMesh(context.get(), request);
  std::vector<v1::MeshChunk> chunks(1);
  ASSERT_TRUE(reader->Read(&chunks[0]));
  // The model disappears: new calls fail, the running stream goes on with
  // the index it resolved.
  testing::RemoveModel(ts.root(), "wide");
  ts.Rescan();
  EXPECT_EQ(ReadMesh(*stub, Ref("wide")).status.error_code(), grpc::StatusCode::NOT_FOUND);
  v1::MeshChunk chunk;
  while (reader->Read(&chunk)) chunks.push_back(chunk);
  const grpc::Status status = reader->Finish();
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(chunks.size(), 401u);
  auto index = index::Index::FromBytes(WideSphereBytes());
  ASSERT_TRUE(index.ok()) << index.status();
  ExpectMeshOfIndex(chunks, **index, 1, 1000);
}

TEST(ServerTest, CancelledGetMeshStops) {
  TestServer ts([](ServerOptions& o) { o.workers = 1; });
  testing::WriteModelVersion(ts.root(), "wide", 1, WideSphereBytes());
  ts.Rescan();
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  v1::GetMeshRequest request;
  *request.mutable_model() = Ref("wide");
  auto context = Context();
  auto reader = stub->GetMesh(context.get(), request);
  v1::MeshChunk chunk;
  ASSERT_TRUE(reader->Read(&chunk));  // 1.5 MiB of the 9.6 MiB of positions
  EXPECT_EQ(chunk.vertex_offset(), 0u);
  context->TryCancel();
  int more = 0;
  while (reader->Read(&chunk)) ++more;
  EXPECT_LT(more, 6);
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (ts.server().service().active_streams() > 0 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(ts.server().service().active_streams(), 0);
  EXPECT_THAT(ts.server().metrics().Text(),
              HasSubstr("geodex_requests_total{code=\"CANCELLED\",method=\"GetMesh\""));
}

TEST(ServerTest, SlowReaderStopsTheStream) {
  TestServer ts([](ServerOptions& o) {
    o.workers = 1;
    o.limits.stream_window = 2;
  });
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto context = Context(60);
  auto stream = stub->StreamDistances(context.get());
  v1::DistanceBatch batch;
  *batch.mutable_model() = Ref("sphere");
  *batch.mutable_a() = ToProto(testing::RandomPoints(1280, 2000, 1));
  *batch.mutable_b() = ToProto(testing::RandomPoints(1280, 2000, 2));
  constexpr int kBatches = 1500;  // ~170 MB of requests, ~24 MB of answers
  std::atomic<int> written{0};
  std::thread writer([&] {
    for (int k = 0; k < kBatches; ++k) {
      batch.set_batch_id(k);
      if (!stream->Write(batch)) break;
      ++written;
    }
    stream->WritesDone();
  });
  // Nobody reads: the server stops reading, and the writer blocks. Wait
  // until it has not advanced for 300 ms.
  int stalled_at = -1;
  const auto stall_until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < stall_until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const int now = written.load();
    if (now == stalled_at) break;
    stalled_at = now;
  }
  EXPECT_LT(stalled_at, kBatches);
  std::printf("slow reader: the writer stalled after %d of %d batches\n", stalled_at, kBatches);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_LE(written.load() - stalled_at, 2);  // still not advancing
  // Reading lets the writer go on again.
  v1::DistanceResult result;
  for (int read = 0; read < 100; ++read) {
    ASSERT_TRUE(stream->Read(&result));
    ASSERT_EQ(result.error_code(), 0) << result.error_message();
    ASSERT_EQ(result.batch_id(), static_cast<uint64_t>(read));
  }
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (written.load() <= stalled_at + 20 && std::chrono::steady_clock::now() < until) {
    ASSERT_TRUE(stream->Read(&result));
  }
  EXPECT_GT(written.load(), stalled_at + 20);
  context->TryCancel();
  while (stream->Read(&result)) {
  }
  writer.join();
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
}

// --- models changing while serving -----------------------------------------------------

TEST(ServerTest, AddReplaceRemoveWhileStreamingFailsNoBatch) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto v1_engine = ReferenceEngine(testing::SphereIndexBytes());
  auto v2_engine = ReferenceEngine(OtherSphereBytes());
  const int32_t faces = v1_engine->index().num_faces();
  ASSERT_EQ(faces, v2_engine->index().num_faces());

  auto context = Context(60);
  auto stream = stub->StreamDistances(context.get());
  std::atomic<bool> stop{false};
  std::atomic<int> sent{0};
  std::thread writer([&] {
    for (int k = 0; !stop; ++k) {
      v1::DistanceBatch batch;
      batch.set_batch_id(k);
      *batch.mutable_model() = Ref("sphere");
      *batch.mutable_a() = ToProto(testing::RandomPoints(faces, 50, k));
      *batch.mutable_b() = ToProto(testing::RandomPoints(faces, 50, k + 1000000));
      if (!stream->Write(batch)) break;
      ++sent;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    stream->WritesDone();
  });
  std::map<int64_t, int> by_version;
  std::atomic<int> read{0};
  int failed = 0, wrong = 0;
  std::thread reader([&] {
    v1::DistanceResult result;
    while (stream->Read(&result)) {
      const int k = static_cast<int>(result.batch_id());
      if (k != read) ++wrong;
      ++read;
      if (result.error_code() != 0) {
        ++failed;
        ADD_FAILURE() << "batch " << k << ": " << result.error_message();
        continue;
      }
      ++by_version[result.version()];
      auto a = testing::RandomPoints(faces, 50, k),
           b = testing::RandomPoints(faces, 50, k + 1000000);
      std::vector<double> expected(50);
      const auto& engine = result.version() == 1 ? v1_engine : v2_engine;
      EXPECT_TRUE(engine->DistanceBatch(a, b, expected).ok());
      for (int i = 0; i < 50; ++i) {
        if (result.distances(i) != expected[i]) ++wrong;
      }
    }
  });
  auto wait_for_batches = [&](int n) {
    const int target = read + n;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (read < target && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  };
  wait_for_batches(20);
  testing::WriteModelVersion(ts.root(), "added", 1, testing::TorusIndexBytes());  // add
  ts.Rescan();
  wait_for_batches(20);
  testing::WriteModelVersion(ts.root(), "sphere", 2, OtherSphereBytes());  // replace
  ts.Rescan();
  wait_for_batches(20);
  testing::RemoveModel(ts.root(), "torus");  // remove
  ts.Rescan();
  wait_for_batches(20);
  stop = true;
  writer.join();
  reader.join();
  EXPECT_TRUE(stream->Finish().ok());
  EXPECT_EQ(read, sent.load());
  EXPECT_EQ(failed, 0);
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(by_version[1], 0);
  EXPECT_GT(by_version[2], 0);

  v1::ListModelsResponse list;
  auto c = Context();
  ASSERT_TRUE(stub->ListModels(c.get(), {}, &list).ok());
  std::set<std::string> names;
  for (const auto& m : list.models()) names.insert(m.name());
  EXPECT_EQ(names, (std::set<std::string>{"added", "sphere"}));
}

TEST(ServerTest, CorruptIndexFailsThatModelOnly) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  // A new model whose only version is corrupt (a flipped byte in a section),
  // and a truncated new version of a served model.
  std::string corrupt = OtherSphereBytes();
  corrupt[corrupt.size() / 2] ^= 0x5a;
  testing::WriteModelVersion(ts.root(), "broken", 1, corrupt);
  testing::WriteModelVersion(ts.root(), "sphere", 2,
                             OtherSphereBytes().substr(0, OtherSphereBytes().size() - 100));
  ts.Rescan();

  v1::GetModelRequest get;
  v1::ModelInfo info;
  *get.mutable_model() = Ref("broken");
  auto context = Context();
  ASSERT_TRUE(stub->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::ModelInfo::FAILED);
  EXPECT_THAT(info.reason(), HasSubstr("version 1: DATA_LOSS"));
  EXPECT_THAT(info.reason(), HasSubstr("checksum"));

  *get.mutable_model() = Ref("sphere");
  context = Context();
  ASSERT_TRUE(stub->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::ModelInfo::FAILED);
  EXPECT_THAT(info.reason(), HasSubstr("version 2: DATA_LOSS"));
  EXPECT_EQ(info.version(), 1);  // still served
  EXPECT_EQ(info.available_versions_size(), 2);

  // The broken model is unavailable; the others keep answering.
  v1::DistanceRequest request;
  *request.mutable_a() = ToProto(testing::RandomPoints(100, 3, 1));
  *request.mutable_b() = ToProto(testing::RandomPoints(100, 3, 2));
  v1::DistanceResponse response;
  *request.mutable_model() = Ref("broken");
  context = Context();
  grpc::Status s = stub->Distance(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("failed to load"));
  for (const char* model : {"sphere", "torus"}) {
    *request.mutable_model() = Ref(model);
    context = Context();
    EXPECT_TRUE(stub->Distance(context.get(), request, &response).ok()) << model;
    EXPECT_EQ(response.version(), 1);
  }
  EXPECT_EQ(HealthCheck(ts.TcpChannel(), "broken"), 2);  // NOT_SERVING
  EXPECT_EQ(HealthCheck(ts.TcpChannel(), "sphere"), 1);
}

TEST(ServerTest, LoadingModelIsUnavailable) {
  std::latch entered(1), release(1);
  std::atomic<bool> hold{false};
  TestServer ts([&](ServerOptions& o) {
    o.before_load = [&](const std::string& path) {
      if (hold && path.find("/late/") != std::string::npos) {
        entered.count_down();
        release.wait();
      }
    };
  });
  hold = true;
  testing::WriteModelVersion(ts.root(), "late", 1, testing::SphereIndexBytes());
  ts.server().registry().TriggerRescan();
  entered.wait();
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("late");
  v1::DistanceResponse response;
  auto context = Context();
  grpc::Status s = stub->Distance(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("is loading"));
  v1::GetModelRequest get;
  *get.mutable_model() = Ref("late");
  v1::ModelInfo info;
  context = Context();
  ASSERT_TRUE(stub->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::ModelInfo::LOADING);
  EXPECT_EQ(HealthCheck(ts.TcpChannel(), "late"), 2);
  release.count_down();
  ts.Rescan();
  context = Context();
  ASSERT_TRUE(stub->GetModel(context.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::ModelInfo::SERVING);
  EXPECT_EQ(HealthCheck(ts.TcpChannel(), "late"), 1);
}

TEST(ServerTest, PairsOnDifferentComponentsAreUnreachable) {
  TestServer ts;
  const int n = 12;  // two unit grids of n x n cells: faces [0, 2n^2) and [2n^2, 4n^2)
  testing::WriteModelVersion(ts.root(), "two", 1,
                             testing::BuildIndexBytes(mesh::gen::TwoComponents(n), 40));
  ts.Rescan();
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  std::vector<mesh::SurfacePoint> a = {{0, {1.0 / 3, 1.0 / 3, 1.0 / 3}}, {0, {1, 0, 0}}};
  std::vector<mesh::SurfacePoint> b = {{2 * n * n + 5, {1.0 / 3, 1.0 / 3, 1.0 / 3}},
                                       {2 * n * n - 1, {0, 1, 0}}};
  v1::PathRequest request;
  *request.mutable_model() = Ref("two");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  v1::PathResponse response;
  auto context = Context();
  ASSERT_TRUE(stub->Path(context.get(), request, &response).ok());
  ASSERT_EQ(response.paths_size(), 2);
  EXPECT_TRUE(std::isinf(response.paths(0).length()));
  EXPECT_EQ(response.paths(0).points().faces_size(), 0);
  EXPECT_GT(response.paths(1).points().faces_size(), 1);
  EXPECT_TRUE(std::isfinite(response.paths(1).length()));

  v1::DistanceRequest distance;
  *distance.mutable_model() = Ref("two");
  *distance.mutable_a() = ToProto(a);
  *distance.mutable_b() = ToProto(b);
  v1::DistanceResponse answer;
  context = Context();
  ASSERT_TRUE(stub->Distance(context.get(), distance, &answer).ok());
  EXPECT_TRUE(std::isinf(answer.distances(0)));
  EXPECT_TRUE(std::isfinite(answer.distances(1)));
}

// --- shutdown -------------------------------------------------------------------------

TEST(ServerTest, ShutdownDuringAStreamDrainsIt) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto context = Context(60);
  auto stream = stub->StreamDistances(context.get());
  std::atomic<bool> stop{false};
  std::atomic<int> sent{0};
  std::thread writer([&] {
    for (int k = 0; !stop; ++k) {
      v1::DistanceBatch batch;
      batch.set_batch_id(k);
      *batch.mutable_model() = Ref("sphere");
      *batch.mutable_a() = ToProto(testing::RandomPoints(1280, 200, k));
      *batch.mutable_b() = ToProto(testing::RandomPoints(1280, 200, k + 7));
      if (!stream->Write(batch)) break;
      ++sent;
    }
  });
  v1::DistanceResult result;
  int read = 0;
  while (read < 50 && stream->Read(&result)) {
    ASSERT_EQ(result.error_code(), 0);
    ++read;
  }
  const auto start = std::chrono::steady_clock::now();
  std::thread shutdown([&] { ts.server().Shutdown(absl::Seconds(10)); });
  while (stream->Read(&result)) {
    EXPECT_EQ(result.error_code(), 0) << result.error_message();  // answered batches are whole
    EXPECT_EQ(result.batch_id(), static_cast<uint64_t>(read));
    ++read;
  }
  stop = true;
  writer.join();
  grpc::Status s = stream->Finish();
  shutdown.join();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE) << s.error_message();
  EXPECT_THAT(s.error_message(), HasSubstr("shutting down"));
  EXPECT_THAT(s.error_message(), HasSubstr(absl::StrFormat("%d batches answered", read)));
  EXPECT_LT(seconds, 5);  // drained, not cut off at the deadline
  // New calls are refused.
  v1::ListModelsResponse list;
  auto c = Context(2);
  EXPECT_FALSE(stub->ListModels(c.get(), {}, &list).ok());
}

TEST(ServerTest, ShutdownFinishesAnIdleStream) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto context = Context(60);
  auto stream = stub->StreamDistances(context.get());
  v1::DistanceBatch batch;
  batch.set_batch_id(1);
  *batch.mutable_model() = Ref("sphere");
  *batch.mutable_a() = ToProto(testing::RandomPoints(1280, 2, 1));
  *batch.mutable_b() = ToProto(testing::RandomPoints(1280, 2, 2));
  ASSERT_TRUE(stream->Write(batch));
  v1::DistanceResult result;
  ASSERT_TRUE(stream->Read(&result));
  const auto start = std::chrono::steady_clock::now();
  ts.server().Shutdown(absl::Seconds(10));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 3);
  EXPECT_FALSE(stream->Read(&result));
  grpc::Status s = stream->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("1 batches answered (last batch id 1)"));
}

// --- health, reflection, metrics ------------------------------------------------------

TEST(ServerTest, HealthOverallAndPerModel) {
  TestServer ts;
  auto channel = ts.TcpChannel();
  EXPECT_EQ(HealthCheck(channel, ""), 1);
  EXPECT_EQ(HealthCheck(channel, "geodex.v1.Geodex"), 1);
  EXPECT_EQ(HealthCheck(channel, "sphere"), 1);
  EXPECT_EQ(HealthCheck(channel, "nope"), -static_cast<int>(grpc::StatusCode::NOT_FOUND));
  testing::RemoveModel(ts.root(), "torus");
  ts.Rescan();
  EXPECT_EQ(HealthCheck(channel, "torus"), 2);
}

TEST(ServerTest, HealthIsAliveButNotReadyDuringTheFirstScan) {
  std::latch entered(1), release(1);
  std::atomic<bool> first{true};
  ServerOptions options;
  testing::TempDir dir;
  testing::WriteModelVersion(dir.path(), "sphere", 1, testing::SphereIndexBytes());
  options = DefaultOptions(dir.path());
  options.before_load = [&](const std::string&) {
    if (first.exchange(false)) {
      entered.count_down();
      release.wait();
    }
  };
  auto server = GeodexServer::Start(options);
  ASSERT_TRUE(server.ok()) << server.status();
  entered.wait();
  auto channel = grpc::CreateChannel(absl::StrFormat("127.0.0.1:%d", (*server)->port()),
                                     grpc::InsecureChannelCredentials());
  EXPECT_EQ(HealthCheck(channel, ""), 2);                  // not ready
  EXPECT_EQ(HealthCheck(channel, "geodex.v1.Geodex"), 1);  // alive
  release.count_down();
  (*server)->registry().RescanNow();
  EXPECT_EQ(HealthCheck(channel, ""), 1);
  (*server)->Shutdown(absl::Seconds(1));
  EXPECT_NE(HealthCheck(channel, ""), 1);
}

TEST(ServerTest, ReflectionListsTheService) {
  TestServer ts;
  grpc::GenericStub stub(ts.TcpChannel());
  grpc::CompletionQueue cq;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  auto call = stub.PrepareCall(
      &context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &cq);
  void* tag;
  bool ok;
  auto step = [&](intptr_t expected) {
    ASSERT_TRUE(cq.Next(&tag, &ok));
    EXPECT_EQ(reinterpret_cast<intptr_t>(tag), expected);
    EXPECT_TRUE(ok);
  };
  call->StartCall(reinterpret_cast<void*>(1));
  step(1);
  const std::string request("\x3a\x00", 2);  // list_services: ""
  grpc::Slice slice(request);
  grpc::ByteBuffer buffer(&slice, 1);
  call->Write(buffer, reinterpret_cast<void*>(2));
  step(2);
  grpc::ByteBuffer response;
  call->Read(&response, reinterpret_cast<void*>(3));
  step(3);
  call->WritesDone(reinterpret_cast<void*>(4));
  step(4);
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(5));
  step(5);
  EXPECT_TRUE(status.ok()) << status.error_message();
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(response.Dump(&slices).ok());
  std::string bytes;
  for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  EXPECT_THAT(bytes, HasSubstr("geodex.v1.Geodex"));
  EXPECT_THAT(bytes, HasSubstr("grpc.health.v1.Health"));
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
}

TEST(ServerTest, MetricsAreServedOverHttp) {
  TestServer ts([](ServerOptions& o) { o.metrics_listen = "127.0.0.1:0"; });
  ASSERT_GT(ts.server().metrics_port(), 0);
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(testing::RandomPoints(1280, 7, 1));
  *request.mutable_b() = ToProto(testing::RandomPoints(1280, 7, 2));
  v1::DistanceResponse response;
  auto context = Context();
  ASSERT_TRUE(stub->Distance(context.get(), request, &response).ok());
  *request.mutable_model() = Ref("unknown-model");
  context = Context();
  ASSERT_FALSE(stub->Distance(context.get(), request, &response).ok());
  const std::string text = HttpGet(ts.server().metrics_port(), "/metrics");
  EXPECT_THAT(text, HasSubstr("200 OK"));
  EXPECT_THAT(
      text, HasSubstr("geodex_requests_total{code=\"OK\",method=\"Distance\",model=\"sphere\"} 1"));
  EXPECT_THAT(text, HasSubstr("geodex_pairs_total{method=\"Distance\",model=\"sphere\"} 7"));
  EXPECT_THAT(text, HasSubstr("geodex_errors_total{code=\"NOT_FOUND\",method=\"Distance\"} 1"));
  EXPECT_THAT(text, HasSubstr("geodex_request_duration_seconds_bucket{method=\"Distance\""));
  EXPECT_THAT(text, HasSubstr("geodex_model_state{model=\"sphere\",state=\"SERVING\"} 1"));
  EXPECT_THAT(text, HasSubstr(absl::StrFormat("geodex_model_mapped_bytes{model=\"sphere\"} %d",
                                              testing::SphereIndexBytes().size())));
  EXPECT_EQ(text.find("unknown-model"), std::string::npos);  // no label for unknown names
}

// --- security ------------------------------------------------------------------------

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

// --- the geodex-server binary: flags, SIGHUP, SIGTERM -----------------------------------

struct Process {
  pid_t pid = -1;
  int port = 0;
};

// Starts geodex-server with `args`; reads the port it prints on stdout.
Process Spawn(std::vector<std::string> args) {
  args.insert(args.begin(), GEODEX_SERVER_BINARY);
  int out[2];
  if (pipe(out) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    close(out[0]);
    close(out[1]);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(out[1]);
  Process p;
  p.pid = pid;
  FILE* in = fdopen(out[0], "r");
  char line[256];
  while (std::fgets(line, sizeof(line), in) != nullptr) {
    if (std::sscanf(line, "listening on port %d", &p.port) == 1) break;
  }
  fclose(in);
  return p;
}

int ExitCode(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(ServerBinaryTest, BadFlagsExitWithTwo) {
  Process p = Spawn({"--listen", "127.0.0.1:0"});  // no --models
  EXPECT_EQ(ExitCode(p.pid), 2);
  p = Spawn({"--models", "/nonexistent/dir", "--listen", "127.0.0.1:0"});
  EXPECT_EQ(ExitCode(p.pid), 2);
  testing::TempDir dir;
  p = Spawn({"--models", dir.path(), "--listen", "127.0.0.1:0", "--workers", "-1"});
  EXPECT_EQ(ExitCode(p.pid), 2);
}

TEST(ServerBinaryTest, SighupRescansAndSigtermDrains) {
  testing::TempDir dir;
  testing::WriteModelVersion(dir.path(), "sphere", 1, testing::SphereIndexBytes());
  Process p = Spawn({"--models", dir.path(), "--listen", "127.0.0.1:0", "--poll-seconds", "0",
                     "--workers", "1", "--log-level", "warn"});
  ASSERT_GT(p.port, 0);
  auto stub = v1::Geodex::NewStub(grpc::CreateChannel(absl::StrFormat("127.0.0.1:%d", p.port),
                                                      grpc::InsecureChannelCredentials()));
  auto count_serving = [&] {
    v1::ListModelsResponse list;
    auto context = Context(5);
    if (!stub->ListModels(context.get(), {}, &list).ok()) return -1;
    int n = 0;
    for (const auto& m : list.models()) n += m.state() == v1::ModelInfo::SERVING;
    return n;
  };
  auto wait_for = [&](int n) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (count_serving() != n && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return count_serving() == n;
  };
  ASSERT_TRUE(wait_for(1));
  testing::WriteModelVersion(dir.path(), "torus", 1, testing::TorusIndexBytes());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(count_serving(), 1);  // no polling: not seen yet
  kill(p.pid, SIGHUP);
  EXPECT_TRUE(wait_for(2));

  // SIGTERM during a stream: it is drained and the process exits 0.
  auto context = Context(30);
  auto stream = stub->StreamDistances(context.get());
  v1::DistanceBatch batch;
  batch.set_batch_id(5);
  *batch.mutable_model() = Ref("sphere");
  *batch.mutable_a() = ToProto(testing::RandomPoints(1280, 3, 1));
  *batch.mutable_b() = ToProto(testing::RandomPoints(1280, 3, 2));
  ASSERT_TRUE(stream->Write(batch));
  v1::DistanceResult result;
  ASSERT_TRUE(stream->Read(&result));
  EXPECT_EQ(result.error_code(), 0);
  kill(p.pid, SIGTERM);
  EXPECT_FALSE(stream->Read(&result));
  grpc::Status s = stream->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("shutting down"));
  EXPECT_EQ(ExitCode(p.pid), 0);
}

}  // namespace
}  // namespace geodex::server
