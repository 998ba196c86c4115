// End-to-end tests of geodex-server's streaming RPCs (StreamDistances,
// Matrix, DistanceField, ExpMap, GetMesh): order, chunking, cancellation and
// backpressure, against the core engine on the same index bytes.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "core/mesh/generators.h"
#include "core/query/exp_map.h"
#include "core/query/input_queries.h"
#include "core/query/engine/query_types.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/server_testing.h"

namespace geodex::server {
namespace {

using testing::Context;
using ::testing::HasSubstr;
using testing::Ref;
using testing::ReferenceEngine;
using testing::RpcTest;
using ::testing::StartsWith;
using testing::TestServer;
using testing::ToProto;

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

// --- every streaming RPC against the engine, in-process and over loopback -----------

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

TEST_P(RpcTest, StreamAndMatrixReturnBoundsWhenAsked) {
  const int32_t faces = sphere_->index().num_faces();
  const auto a = testing::RandomPoints(faces, 60, 41), b = testing::RandomPoints(faces, 60, 42);
  std::vector<double> expected(60), bounds(60);
  ASSERT_TRUE(sphere_->DistanceBatch(a, b, expected, {.tolerance = 0.01}, nullptr, bounds).ok());
  auto context = Context();
  auto stream = stub_->StreamDistances(context.get());
  v1::DistanceBatch batch;
  batch.set_batch_id(1);
  *batch.mutable_model() = Ref("sphere");
  *batch.mutable_a() = ToProto(a);
  *batch.mutable_b() = ToProto(b);
  batch.set_tolerance(0.01);
  batch.set_error_bounds(true);
  ASSERT_TRUE(stream->Write(batch));
  stream->WritesDone();
  v1::DistanceResult result;
  ASSERT_TRUE(stream->Read(&result));
  ASSERT_EQ(result.error_code(), 0) << result.error_message();
  ASSERT_EQ(result.bounds_size(), 60);
  for (int i = 0; i < 60; ++i) {
    EXPECT_EQ(result.distances(i), expected[i]);
    EXPECT_EQ(result.bounds(i), bounds[i]);
  }
  EXPECT_TRUE(stream->Finish().ok());

  v1::MatrixRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_sources() = ToProto(std::span(a).first(3));
  *request.mutable_targets() = ToProto(b);
  request.set_error_bounds(true);
  auto matrix_context = Context();
  auto reader = stub_->Matrix(matrix_context.get(), request);
  v1::MatrixBlock block;
  int64_t rows = 0;
  while (reader->Read(&block)) {
    ASSERT_EQ(block.bounds_size(), block.values_size());
    for (int64_t r = 0; r < block.rows(); ++r) {
      for (int t = 0; t < 60; ++t) {
        double bound = -1;
        const double d = *sphere_->Distance(a[block.row_offset() + r], b[t], {}, nullptr, &bound);
        EXPECT_EQ(block.values(r * 60 + t), d);
        EXPECT_EQ(block.bounds(r * 60 + t), bound);
      }
    }
    rows += block.rows();
  }
  EXPECT_EQ(rows, 3);
  EXPECT_TRUE(reader->Finish().ok());
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

// With a radius: the sparse form, the engine's exact field within it (the
// sphere's index needed no repair: input ids are internal ids).
TEST_P(RpcTest, DistanceFieldWithinARadiusMatchesTheEngine) {
  const int32_t faces = sphere_->index().num_faces();
  const auto sources = testing::RandomPoints(faces, 2, 22);
  for (const bool nearest : {false, true}) {
    v1::DistanceFieldRequest request;
    *request.mutable_model() = Ref("sphere");
    *request.mutable_sources() = ToProto(sources);
    request.set_with_nearest_source(nearest);
    request.set_radius(0.6);
    auto context = Context();
    auto reader = stub_->DistanceField(context.get(), request);
    query::QueryScratch scratch;
    auto field = sphere_->FieldWithin(sources, {.radius = 0.6}, scratch);
    ASSERT_TRUE(field.ok()) << field.status();
    ASSERT_FALSE(field->vertices.empty());
    ASSERT_LT(field->vertices.size(), 300u);  // under the test server's max_field_vertices
    v1::DistanceFieldChunk chunk;
    int64_t next = 0;
    int chunks = 0;
    while (reader->Read(&chunk)) {
      ++chunks;
      EXPECT_EQ(chunk.vertex_offset(), next);
      EXPECT_EQ(chunk.num_vertices(), static_cast<int64_t>(field->vertices.size()));
      EXPECT_EQ(chunk.version(), 1);
      ASSERT_EQ(chunk.vertices_size(), chunk.distances_size());
      ASSERT_EQ(chunk.nearest_source_size(), nearest ? chunk.distances_size() : 0);
      for (int i = 0; i < chunk.distances_size(); ++i) {
        EXPECT_EQ(chunk.vertices(i), field->vertices[next + i]);
        EXPECT_EQ(chunk.distances(i), field->distance[next + i]);
        EXPECT_LE(chunk.distances(i), 0.6);
        if (nearest) {
          EXPECT_EQ(chunk.nearest_source(i), field->nearest[next + i]);
        }
      }
      next += chunk.distances_size();
    }
    ASSERT_TRUE(reader->Finish().ok());
    EXPECT_EQ(chunks, 1);
    EXPECT_EQ(next, static_cast<int64_t>(field->vertices.size()));
  }
  // Bad radii are refused with the value; a tiny one inside a face answers
  // one empty chunk that still carries the version.
  for (const double radius :
       {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    v1::DistanceFieldRequest request;
    *request.mutable_model() = Ref("sphere");
    *request.mutable_sources() = ToProto(sources);
    request.set_radius(radius);
    auto context = Context();
    auto reader = stub_->DistanceField(context.get(), request);
    v1::DistanceFieldChunk chunk;
    EXPECT_FALSE(reader->Read(&chunk));
    const grpc::Status s = reader->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << radius;
    EXPECT_THAT(s.error_message(), HasSubstr("radius must be finite and > 0, got"));
  }
  v1::DistanceFieldRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_sources() = ToProto(std::vector<mesh::SurfacePoint>{{0, {0.3, 0.3, 0.4}}});
  request.set_radius(1e-6);
  auto context = Context();
  auto reader = stub_->DistanceField(context.get(), request);
  std::vector<v1::DistanceFieldChunk> chunks;
  v1::DistanceFieldChunk chunk;
  while (reader->Read(&chunk)) chunks.push_back(chunk);
  ASSERT_TRUE(reader->Finish().ok());
  ASSERT_EQ(chunks.size(), 1u);
  EXPECT_EQ(chunks[0].num_vertices(), 0);
  EXPECT_EQ(chunks[0].distances_size(), 0);
  EXPECT_EQ(chunks[0].version(), 1);
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

// --- chunking, cancellation, backpressure, admission (loopback) -----------------------

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

// The value of the first sample of `metric` whose labels contain `label` in
// the Prometheus text `text`, or -1.
double MetricValue(const std::string& text, const std::string& metric, const std::string& label) {
  size_t at = 0;
  while ((at = text.find(metric + "{", at)) != std::string::npos) {
    const size_t end = text.find('\n', at);
    const std::string line = text.substr(at, end - at);
    at = end;
    if (line.find(label) == std::string::npos) continue;
    return std::stod(line.substr(line.rfind(' ') + 1));
  }
  return -1;
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
  const std::string text = ts.server().metrics().Text();
  EXPECT_THAT(text, HasSubstr("geodex_requests_total{code=\"CANCELLED\",method=\"Matrix\""));
  // The rows stopped: the call's cells (rows computed and handed to gRPC x
  // 2000 targets) are the two rows read and the few in flight at the cancel,
  // far fewer than the 2000 rows asked for.
  const double cells = MetricValue(text, "geodex_pairs_total", "method=\"Matrix\"");
  EXPECT_GE(cells, 2 * 2000);
  EXPECT_LE(cells, 50 * 2000) << "the server kept computing rows of a cancelled Matrix";
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

// Reads an ExpMap stream to its end.
struct ExpMapReply {
  grpc::Status status;
  std::vector<v1::ExpMapChunk> chunks;
};
ExpMapReply ReadExpMap(v1::Geodex::Stub& stub, const v1::ExpMapRequest& request) {
  auto context = Context();
  auto reader = stub.ExpMap(context.get(), request);
  ExpMapReply reply;
  v1::ExpMapChunk chunk;
  while (reader->Read(&chunk)) reply.chunks.push_back(chunk);
  reply.status = reader->Finish();
  return reply;
}

TEST(ServerTest, ExpMapIsTheFacadesToTheBit) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  v1::ExpMapRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_center() = ToProto(std::vector<mesh::SurfacePoint>{{17, {0.2, 0.3, 0.5}}});
  request.set_radius(1.5);
  request.set_near_pairs(v1::NEAR_PAIRS_UNFOLD);
  for (double x : {0.3, -1.0, 0.2}) request.mutable_reference_direction()->add_xyz(x);
  const ExpMapReply reply = ReadExpMap(*stub, request);
  ASSERT_TRUE(reply.status.ok()) << reply.status.error_message();
  ASSERT_EQ(reply.chunks.size(), 1u);
  const v1::ExpMapChunk& chunk = reply.chunks[0];
  EXPECT_EQ(chunk.version(), 1);

  // The facade's map over the same index bytes, as the server answers it.
  auto queries = query::InputQueries::Create(ReferenceEngine(testing::SphereIndexBytes()));
  ASSERT_TRUE(queries.ok()) << queries.status();
  const mesh::SurfacePoint centre{17, {0.2, 0.3, 0.5}};
  query::EnginePoints read;
  ASSERT_TRUE((*queries)->Read(std::span(&centre, 1), query::Named("center"), &read).ok());
  query::ExpMapOptions options;
  options.radius = 1.5;
  options.reference_direction = mesh::Vec3(0.3, -1.0, 0.2);
  options.distance.near_pairs = query::NearPairs::kUnfold;
  auto map = query::ExpMap(**queries, read, 0, options);
  ASSERT_TRUE(map.ok()) << map.status();
  ASSERT_GT(map->size(), 50u);
  ASSERT_EQ(chunk.num_vertices(), static_cast<int64_t>(map->size()));
  ASSERT_EQ(chunk.vertices_size(), static_cast<int>(map->size()));
  for (size_t i = 0; i < map->size(); ++i) {
    EXPECT_EQ(chunk.vertices(i), (*map)[i].vertex);
    EXPECT_EQ(chunk.r(i), (*map)[i].r);
    EXPECT_EQ(chunk.theta(i), (*map)[i].theta);
    EXPECT_EQ(chunk.u(i), (*map)[i].u);
    EXPECT_EQ(chunk.v(i), (*map)[i].v);
  }
}

TEST(ServerTest, ExpMapRejectsBadRequests) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto request = [](std::vector<mesh::SurfacePoint> centre, double radius) {
    v1::ExpMapRequest r;
    *r.mutable_model() = Ref("sphere");
    *r.mutable_center() = ToProto(centre);
    r.set_radius(radius);
    return r;
  };
  const mesh::SurfacePoint good{3, {1, 0, 0}};
  ExpMapReply reply = ReadExpMap(*stub, request({good, good}, 1));
  EXPECT_EQ(reply.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(reply.status.error_message(), HasSubstr("exactly one point"));
  reply = ReadExpMap(*stub, request({good}, -1));
  EXPECT_EQ(reply.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(reply.status.error_message(), HasSubstr("radius"));
  reply = ReadExpMap(*stub, request({{99999, {1, 0, 0}}}, 1));
  EXPECT_EQ(reply.status.error_code(), grpc::StatusCode::OUT_OF_RANGE);
  v1::ExpMapRequest two_numbers = request({good}, 1);
  two_numbers.mutable_reference_direction()->add_xyz(1);
  two_numbers.mutable_reference_direction()->add_xyz(0);
  reply = ReadExpMap(*stub, two_numbers);
  EXPECT_EQ(reply.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(reply.status.error_message(),
              HasSubstr("reference_direction: give one direction (3 numbers), got 2 numbers"));
  v1::ExpMapRequest negative_tolerance = request({good}, 1);
  negative_tolerance.set_tolerance(-1);
  EXPECT_EQ(ReadExpMap(*stub, negative_tolerance).status.error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  v1::ExpMapRequest unknown = request({good}, 1);
  *unknown.mutable_model() = Ref("no-such-model");
  EXPECT_EQ(ReadExpMap(*stub, unknown).status.error_code(), grpc::StatusCode::NOT_FOUND);
  // The server keeps serving.
  EXPECT_TRUE(ReadExpMap(*stub, request({good}, 0.5)).status.ok());
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
  // Flow control is the subject: the pure O(1) mode keeps each batch quick
  // (on this coarse sphere most pairs are closer than 3L and would be
  // traced), so that a stall means a full window, not a busy worker.
  batch.set_near_pairs(v1::NEAR_PAIRS_UNFOLD);
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
  // until it has not advanced for a second (a busy worker in a sanitizer
  // build can pause it for a few hundred milliseconds without a full window).
  int stalled_at = -1, unchanged = 0;
  const auto stall_until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (unchanged < 4 && std::chrono::steady_clock::now() < stall_until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    const int now = written.load();
    unchanged = now == stalled_at ? unchanged + 1 : 0;
    stalled_at = now;
  }
  EXPECT_LT(stalled_at, kBatches);
  std::printf("slow reader: the writer stalled after %d of %d batches\n", stalled_at, kBatches);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
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

}  // namespace
}  // namespace geodex::server
