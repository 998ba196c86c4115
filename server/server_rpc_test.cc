// End-to-end tests of geodex-server's unary RPCs: a real GeodexServer over a
// temporary model repository, called through the generated gRPC stub, both
// in-process and over a loopback TCP port. Answers are compared with the core
// engine on the same index bytes.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <latch>
#include <limits>
#include <map>
#include <thread>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/str_format.h"
#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "grpcpp/generic/generic_stub.h"
#include "gtest/gtest.h"
#include "server/server_testing.h"

namespace geodex::server {
namespace {

using testing::Context;
using ::testing::HasSubstr;
using testing::HealthCheck;
using testing::Ref;
using testing::ReferenceEngine;
using testing::RpcTest;
using ::testing::StartsWith;
using testing::TestServer;
using testing::ToProto;

// --- every unary RPC against the engine, in-process and over loopback -------------

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

TEST_P(RpcTest, ErrorBoundsAndToleranceMatchTheEngine) {
  v1::DistanceRequest request = SphereRequest(300, 1);
  const int32_t faces = sphere_->index().num_faces();
  auto a = testing::RandomPoints(faces, 300, 1), b = testing::RandomPoints(faces, 300, 1001);
  for (double tolerance : {0.0, 0.005}) {
    request.set_tolerance(tolerance);
    request.set_error_bounds(true);
    v1::DistanceResponse response;
    ASSERT_TRUE(Distance(request, &response).ok());
    ASSERT_EQ(response.bounds_size(), 300);
    std::vector<double> expected(300), bounds(300);
    ASSERT_TRUE(sphere_->DistanceBatch(a, b, expected, {.tolerance = tolerance}, nullptr, bounds)
                    .ok());
    for (int i = 0; i < 300; ++i) {
      EXPECT_EQ(response.distances(i), expected[i]) << i;
      EXPECT_EQ(response.bounds(i), bounds[i]) << i;
      EXPECT_GE(bounds[i], 0);
      if (tolerance > 0) {
        EXPECT_LE(bounds[i], tolerance * expected[i]) << i;
      }
    }
  }
  // Without error_bounds, no bounds.
  request.set_error_bounds(false);
  v1::DistanceResponse response;
  ASSERT_TRUE(Distance(request, &response).ok());
  EXPECT_EQ(response.bounds_size(), 0);
  for (double bad : {-0.1, std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::infinity()}) {
    request.set_tolerance(bad);
    grpc::Status s = Distance(request, &response);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_THAT(s.error_message(), HasSubstr("tolerance"));
  }
}

TEST_P(RpcTest, ExactNearPairsMatchTheExactEngine) {
  auto exact = ReferenceEngine(testing::SphereIndexBytes());
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
  ASSERT_TRUE(exact->DistanceBatch(a, b, expected, {.near_pairs = query::NearPairs::kExact}, &scratch).ok());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(response.distances(i), expected[i]) << i;
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
  {  // vertices a field within a radius reaches: the whole sphere > 300
    v1::DistanceFieldRequest request;
    *request.mutable_model() = Ref("sphere");
    *request.mutable_sources() = ToProto(testing::RandomPoints(faces, 2, 1));
    request.set_radius(10);
    auto context = Context();
    auto reader = stub_->DistanceField(context.get(), request);
    v1::DistanceFieldChunk chunk;
    EXPECT_FALSE(reader->Read(&chunk));
    s = reader->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(s.error_message(), HasSubstr("more than 300 vertices"));
    EXPECT_THAT(s.error_message(), HasSubstr("max_field_vertices"));
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

// --- near-pair modes, limits, deadlines, overload (loopback) --------------------------

TEST(ServerTest, PerModelConfigLowersLimitsAndForcesExactNearPairs) {
  TestServer ts;
  testing::WriteModelConfig(ts.root(), "sphere",
                            "exact_near_pairs: true\nlimits { max_pairs_per_message: 10 }\n");
  ts.Rescan();
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto exact = ReferenceEngine(testing::SphereIndexBytes());
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
  ASSERT_TRUE(exact->DistanceBatch(a, b, expected, {.near_pairs = query::NearPairs::kExact}, &scratch).ok());
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
  ASSERT_TRUE(
      by_path->DistanceBatch(a, b, expected_unfold, {.near_pairs = query::NearPairs::kUnfold})
          .ok());
  ASSERT_NE(expected_path, expected_unfold);
  EXPECT_EQ(answers(), expected_path);
  testing::WriteModelConfig(ts.root(), "sphere", "unfold_near_pairs: true\n");
  ts.Rescan();
  EXPECT_EQ(answers(), expected_unfold);
  // A request's own mode wins over the model's.
  request.set_near_pairs(v1::NEAR_PAIRS_PATH);
  EXPECT_EQ(answers(), expected_path);
}

TEST(ServerTest, ModelToleranceAppliesAndBoundsNeedACalibratedIndex) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  auto sphere = ReferenceEngine(testing::SphereIndexBytes());
  const int32_t faces = sphere->index().num_faces();
  const auto a = testing::RandomPoints(faces, 50, 5), b = testing::RandomPoints(faces, 50, 6);
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  request.set_error_bounds(true);
  testing::WriteModelConfig(ts.root(), "sphere", "tolerance: 0.002\n");
  ts.Rescan();
  v1::DistanceResponse response;
  auto context = Context();
  ASSERT_TRUE(stub->Distance(context.get(), request, &response).ok());
  std::vector<double> expected(50), bounds(50);
  ASSERT_TRUE(sphere->DistanceBatch(a, b, expected, {.tolerance = 0.002}, nullptr, bounds).ok());
  for (int i = 0; i < 50; ++i) {
    EXPECT_EQ(response.distances(i), expected[i]);
    EXPECT_EQ(response.bounds(i), bounds[i]);
  }
  // An index built without its calibration: bounds and tolerances are
  // refused, plain distances still answered.
  testing::WriteModelConfig(ts.root(), "sphere", "");
  testing::WriteModelVersion(
      ts.root(), "plain", 1,
      testing::BuildIndexBytes(mesh::gen::Sphere(3, 1.0), 40, /*calibrate=*/false));
  ts.Rescan();
  *request.mutable_model() = Ref("plain");
  context = Context();
  grpc::Status s = stub->Distance(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("calibration"));
  request.set_error_bounds(false);
  context = Context();
  EXPECT_TRUE(stub->Distance(context.get(), request, &response).ok());
  request.set_tolerance(0.01);
  context = Context();
  EXPECT_EQ(stub->Distance(context.get(), request, &response).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
}

TEST(ServerTest, EachRequestMayChooseItsNearPairMode) {
  TestServer ts;
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
  query::QueryScratch scratch;
  const int32_t faces = ReferenceEngine(testing::SphereIndexBytes())->index().num_faces();
  const auto a = testing::RandomPoints(faces, 40, 5);
  auto b = testing::RandomPoints(faces, 40, 6);
  // Near pairs: in the same face, where the path and exact modes both give
  // the straight segment, and in faces of nearby ids (neighbours on the
  // generated sphere), where they differ at least by rounding.
  for (size_t i = 0; i < b.size(); ++i) b[i].face = (a[i].face + i % 3) % faces;
  std::map<v1::NearPairs, std::vector<double>> expected;
  for (auto [wire, mode] : {std::pair{v1::NEAR_PAIRS_PATH, query::NearPairs::kPath},
                            std::pair{v1::NEAR_PAIRS_UNFOLD, query::NearPairs::kUnfold},
                            std::pair{v1::NEAR_PAIRS_EXACT, query::NearPairs::kExact}}) {
    auto engine = ReferenceEngine(testing::SphereIndexBytes());
    expected[wire].resize(a.size());
    ASSERT_TRUE(engine->DistanceBatch(a, b, expected[wire], {.near_pairs = mode}, &scratch).ok());
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
  std::latch blocked(1), release(1);  // outlive the server's pool
  TestServer ts([](ServerOptions& o) { o.workers = 1; });
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
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
  // The latches outlive the server, whose pool joins the blocked worker; the
  // worker is released however the test ends (clang's ASan caught the
  // worker reading `release` after it went out of scope).
  std::latch blocked(1), release(1);
  TestServer ts([](ServerOptions& o) {
    o.workers = 1;
    o.queue_capacity = 1;
  });
  absl::Cleanup unblock = [&release] { release.count_down(); };
  auto stub = v1::Geodex::NewStub(ts.TcpChannel());
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

}  // namespace
}  // namespace geodex::server
