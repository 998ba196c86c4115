// The HTTP/JSON transcoding of `geodex web` against MockGeodexConnection: no
// server, no sockets.

#include "client/cli/web/web_gateway.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <stdexcept>

#include "geodex/client/mocks/mock_geodex_connection.h"
#include "gmock/gmock.h"
#include "google/protobuf/descriptor.h"
#include "google/protobuf/descriptor.pb.h"
#include "google/protobuf/dynamic_message.h"
#include "google/protobuf/text_format.h"
#include "google/protobuf/util/json_util.h"
#include "google/protobuf/util/message_differencer.h"
#include "gtest/gtest.h"

namespace geodex::client::cli {
namespace {

using ::testing::_;
using ::testing::HasSubstr;
using ::testing::Return;

class WebGatewayTest : public ::testing::Test {
 protected:
  WebGatewayTest()
      : mock_(std::make_shared<MockGeodexConnection>()),
        gateway_(mock_, {{"/index.html", {"text/html; charset=utf-8", "<html>viewer</html>"}}},
                 1024) {}

  HttpResponse Get(const std::string& path, std::multimap<std::string, std::string> query = {}) {
    return gateway_.Handle({"GET", path, std::move(query), ""});
  }
  HttpResponse Post(const std::string& path, const std::string& body) {
    return gateway_.Handle({"POST", path, {}, body});
  }

  std::shared_ptr<MockGeodexConnection> mock_;
  WebGateway gateway_;
};

template <class Message>
Message Parse(const HttpResponse& response) {
  Message message;
  EXPECT_EQ(response.content_type, "application/json");
  const auto status = google::protobuf::util::JsonStringToMessage(response.body, &message);
  EXPECT_TRUE(status.ok()) << response.body;
  return message;
}

// The error body's fields, checked to be exactly grpc-gateway's shape.
void ExpectError(const HttpResponse& response, int http_status, absl::StatusCode code,
                 const std::string& message_part) {
  EXPECT_EQ(response.status, http_status) << response.body;
  EXPECT_EQ(response.content_type, "application/json");
  EXPECT_THAT(response.body, HasSubstr(absl::StrCat("{\"code\":", static_cast<int>(code), ",")));
  EXPECT_THAT(response.body, HasSubstr(message_part));
  EXPECT_THAT(response.body, HasSubstr("\"details\":[]}"));
}

TEST(HttpStatusFromCode, IsGrpcGatewaysTable) {
  using C = absl::StatusCode;
  const std::vector<std::pair<C, int>> table = {
      {C::kOk, 200},
      {C::kCancelled, 499},
      {C::kUnknown, 500},
      {C::kInvalidArgument, 400},
      {C::kDeadlineExceeded, 504},
      {C::kNotFound, 404},
      {C::kAlreadyExists, 409},
      {C::kPermissionDenied, 403},
      {C::kResourceExhausted, 429},
      {C::kFailedPrecondition, 400},
      {C::kAborted, 409},
      {C::kOutOfRange, 400},
      {C::kUnimplemented, 501},
      {C::kInternal, 500},
      {C::kUnavailable, 503},
      {C::kDataLoss, 500},
      {C::kUnauthenticated, 401},
  };
  for (const auto& [code, http] : table) {
    EXPECT_EQ(HttpStatusFromCode(code), http) << absl::StatusCodeToString(code);
  }
}

TEST(ErrorResponse, EscapesTheMessage) {
  const HttpResponse r = ErrorResponse(absl::NotFoundError("model \"a\\b\"\n\x01"));
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(r.body, R"({"code":5,"message":"model \"a\\b\"\n\u0001","details":[]})");
}

TEST_F(WebGatewayTest, ListModels) {
  v1::ListModelsResponse answer;
  v1::ModelInfo* info = answer.add_models();
  info->set_name("torus");
  info->set_num_vertices(288);
  info->set_state(v1::ModelInfo::SERVING);
  EXPECT_CALL(*mock_, ListModels).WillOnce(Return(answer));
  const HttpResponse r = Get("/v1/models");
  EXPECT_EQ(r.status, 200);
  // protobuf's JSON mapping: lowerCamelCase, int64 as strings, enums by name,
  // unpopulated fields printed.
  EXPECT_THAT(r.body, HasSubstr(R"("numVertices":"288")"));
  EXPECT_THAT(r.body, HasSubstr(R"("state":"SERVING")"));
  EXPECT_THAT(r.body, HasSubstr(R"("numSamples":"0")"));
  EXPECT_EQ(Parse<v1::ListModelsResponse>(r).models(0).name(), "torus");
}

TEST_F(WebGatewayTest, GetModelTakesTheNameFromThePathAndTheVersionFromTheQuery) {
  EXPECT_CALL(*mock_, GetModel).WillOnce([](const v1::GetModelRequest& request) {
    EXPECT_EQ(request.model().name(), "bunny.v2");
    EXPECT_EQ(request.model().version(), 7);
    v1::ModelInfo info;
    info.set_name("bunny.v2");
    (*info.mutable_build_report())["samples"] = "500";
    return info;
  });
  const HttpResponse r = Get("/v1/models/bunny.v2", {{"version", "7"}});
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(Parse<v1::ModelInfo>(r).build_report().at("samples"), "500");
  ExpectError(Get("/v1/models/bunny", {{"version", "x"}}), 400, absl::StatusCode::kInvalidArgument,
              "not an integer");
  ExpectError(Get("/v1/models/bunny", {{"verzion", "1"}}), 400, absl::StatusCode::kInvalidArgument,
              "unknown query parameter 'verzion'");
}

TEST_F(WebGatewayTest, DistanceRoundTripsEveryDoubleExactly) {
  const double d = 1.2345678901234567, bound = 3.0000000000000004e-7;
  EXPECT_CALL(*mock_, Distance).WillOnce([&](const v1::DistanceRequest& request) {
    EXPECT_EQ(request.model().name(), "torus");
    EXPECT_EQ(request.model().version(), 0);
    EXPECT_EQ(request.a().faces(0), 12);
    EXPECT_EQ(request.a().weights(1), 0.1);
    EXPECT_EQ(request.b().weights(2), 1.0 / 3.0);
    EXPECT_TRUE(request.error_bounds());
    EXPECT_EQ(request.near_pairs(), v1::NEAR_PAIRS_EXACT);
    EXPECT_EQ(request.refine_below(), 8);  // the every-distance mode, in L1000
    v1::DistanceResponse response;
    response.add_distances(d);
    response.add_distances(std::numeric_limits<double>::infinity());
    response.add_bounds(bound);
    response.add_bounds(0);
    response.set_version(4);
    return response;
  });
  const HttpResponse r = Post("/v1/models/torus:distance", R"({
      "a": {"faces": [12], "weights": [0.6, 0.1, 0.3]},
      "b": {"faces": [3], "weights": [0.3333333333333333, 0.3333333333333333, 0.3333333333333333]},
      "errorBounds": true, "near_pairs": "NEAR_PAIRS_EXACT", "refineBelow": 8})");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_THAT(r.body, HasSubstr("\"Infinity\""));
  const v1::DistanceResponse parsed = Parse<v1::DistanceResponse>(r);
  ASSERT_EQ(parsed.distances_size(), 2);
  EXPECT_EQ(parsed.distances(0), d);  // bit for bit
  EXPECT_TRUE(std::isinf(parsed.distances(1)));
  EXPECT_EQ(parsed.bounds(0), bound);
  EXPECT_EQ(parsed.version(), 4);
}

TEST_F(WebGatewayTest, BadBodiesAreRejectedBeforeAnyCall) {
  EXPECT_CALL(*mock_, Distance).Times(0);
  ExpectError(Post("/v1/models/torus:distance", R"({"a": {"faces": [1]}, "tolerence": 0.1})"), 400,
              absl::StatusCode::kInvalidArgument, "tolerence");
  ExpectError(Post("/v1/models/torus:distance", R"({"a": )"), 400,
              absl::StatusCode::kInvalidArgument, "geodex.v1.DistanceRequest");
  ExpectError(Post("/v1/models/torus:distance", R"({"model": {"name": "cube"}})"), 400,
              absl::StatusCode::kInvalidArgument, "names model 'cube'");
  ExpectError(Post("/v1/models/torus:distance", std::string(2000, ' ')), 413,
              absl::StatusCode::kResourceExhausted, "limit is 1024");
}

TEST_F(WebGatewayTest, ServerErrorsKeepTheirCodeAndMessage) {
  EXPECT_CALL(*mock_, Distance)
      .WillOnce(Return(absl::OutOfRangeError("a[0]: face id 99 out of range [0, 10)")))
      .WillOnce(Return(absl::UnavailableError("model torus is loading")))
      .WillOnce(Return(absl::ResourceExhaustedError("server busy")))
      .WillOnce(Return(absl::UnauthenticatedError("missing bearer token")))
      .WillOnce(Return(absl::DeadlineExceededError("deadline exceeded")));
  ExpectError(Post("/v1/models/torus:distance", "{}"), 400, absl::StatusCode::kOutOfRange,
              "face id 99");
  ExpectError(Post("/v1/models/torus:distance", "{}"), 503, absl::StatusCode::kUnavailable,
              "loading");
  ExpectError(Post("/v1/models/torus:distance", ""), 429, absl::StatusCode::kResourceExhausted,
              "busy");
  ExpectError(Post("/v1/models/torus:distance", "{}"), 401, absl::StatusCode::kUnauthenticated,
              "bearer");
  ExpectError(Post("/v1/models/torus:distance", "{}"), 504, absl::StatusCode::kDeadlineExceeded,
              "deadline");
  EXPECT_CALL(*mock_, GetModel).WillOnce(Return(absl::NotFoundError("unknown model 'x'")));
  ExpectError(Get("/v1/models/x"), 404, absl::StatusCode::kNotFound, "unknown model 'x'");
}

TEST_F(WebGatewayTest, RoutesAndMethods) {
  ExpectError(Get("/v1/models/torus:distance"), 405, absl::StatusCode::kUnimplemented, "use POST");
  ExpectError(Post("/v1/models", "{}"), 405, absl::StatusCode::kUnimplemented, "use GET");
  ExpectError(Post("/v1/models/torus:teleport", "{}"), 404, absl::StatusCode::kNotFound,
              "teleport");
  ExpectError(Get("/v1/models/torus/faces"), 404, absl::StatusCode::kNotFound, "no such API path");
  ExpectError(Get("/v1/models/torus:"), 404, absl::StatusCode::kNotFound, "no such method");
  ExpectError(Get("/v1/elsewhere"), 404, absl::StatusCode::kNotFound, "no such API path");
  ExpectError(Get("/v1/models/"), 404, absl::StatusCode::kNotFound, "names no model");
  ExpectError(Get("/secret.txt"), 404, absl::StatusCode::kNotFound, "no such page");
  const HttpResponse page = Get("/");
  EXPECT_EQ(page.status, 200);
  EXPECT_EQ(page.content_type, "text/html; charset=utf-8");
  EXPECT_EQ(page.body, "<html>viewer</html>");
  ExpectError(Post("/", ""), 405, absl::StatusCode::kUnimplemented, "not allowed");
}

TEST_F(WebGatewayTest, PathAndLocate) {
  EXPECT_CALL(*mock_, Path).WillOnce([](const v1::PathRequest& request) {
    EXPECT_EQ(request.model().name(), "torus");
    EXPECT_EQ(request.exact_corridor(), 4u);
    v1::PathResponse response;
    v1::Polyline* p = response.add_paths();
    p->set_length(2.5);
    for (double x : {0.0, 1.0, 2.0, 0.0, 0.0, 0.0}) p->mutable_positions()->add_xyz(x);
    return response;
  });
  const HttpResponse r = Post("/v1/models/torus:path", R"({"exactCorridor": 4})");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(Parse<v1::PathResponse>(r).paths(0).length(), 2.5);

  EXPECT_CALL(*mock_, Locate).WillOnce([](const v1::LocateRequest& request) {
    EXPECT_EQ(request.positions().xyz_size(), 3);
    v1::LocateResponse response;
    response.mutable_points()->add_faces(5);
    return response;
  });
  const HttpResponse l = Post("/v1/models/torus:locate", R"({"positions": {"xyz": [1, 2, 3]}})");
  ASSERT_EQ(l.status, 200) << l.body;
  EXPECT_EQ(Parse<v1::LocateResponse>(l).points().faces(0), 5);
}

TEST_F(WebGatewayTest, FieldChunksAreMergedAndChecked) {
  v1::DistanceFieldChunk c0, c1;
  for (auto* c : {&c0, &c1}) {
    c->set_num_vertices(5);
    c->set_version(2);
  }
  for (double d : {0.0, 1.0, 2.0}) c0.add_distances(d);
  c1.set_vertex_offset(3);
  for (double d : {3.0, std::numeric_limits<double>::infinity()}) c1.add_distances(d);
  EXPECT_CALL(*mock_, DistanceField)
      .WillOnce(Return(std::vector<v1::DistanceFieldChunk>{c0, c1}))
      .WillOnce(Return(std::vector<v1::DistanceFieldChunk>{c1, c0}))
      .WillOnce(Return(std::vector<v1::DistanceFieldChunk>{c0}));
  const std::string body = R"({"sources": {"faces": [0], "weights": [1, 0, 0]}})";
  const HttpResponse r = Post("/v1/models/torus:field", body);
  ASSERT_EQ(r.status, 200) << r.body;
  const auto merged = Parse<v1::DistanceFieldChunk>(r);
  EXPECT_EQ(merged.vertex_offset(), 0);
  EXPECT_EQ(merged.num_vertices(), 5);
  EXPECT_EQ(merged.version(), 2);
  ASSERT_EQ(merged.distances_size(), 5);
  EXPECT_EQ(merged.distances(3), 3.0);
  EXPECT_TRUE(std::isinf(merged.distances(4)));
  ExpectError(Post("/v1/models/torus:field", body), 500, absl::StatusCode::kDataLoss,
              "not contiguous");
  ExpectError(Post("/v1/models/torus:field", body), 500, absl::StatusCode::kDataLoss,
              "every vertex");
}

// With a radius the JSON body carries it, and the sparse chunks merge into
// one: vertices aligned with distances.
TEST_F(WebGatewayTest, FieldWithinARadiusPassesTheRadiusAndMergesVertices) {
  v1::DistanceFieldChunk c0, c1;
  for (auto* c : {&c0, &c1}) {
    c->set_num_vertices(3);
    c->set_version(2);
  }
  c0.add_vertices(4);
  c0.add_distances(0.5);
  c0.add_vertices(9);
  c0.add_distances(1.25);
  c1.set_vertex_offset(2);
  c1.add_vertices(17);
  c1.add_distances(0.75);
  v1::DistanceFieldChunk no_vertices = c1;
  no_vertices.clear_vertices();
  EXPECT_CALL(*mock_, DistanceField)
      .WillOnce([&](const v1::DistanceFieldRequest& request) {
        EXPECT_EQ(request.radius(), 1.5);
        EXPECT_EQ(request.model().name(), "torus");
        return std::vector<v1::DistanceFieldChunk>{c0, c1};
      })
      .WillOnce(Return(std::vector<v1::DistanceFieldChunk>{c0, no_vertices}));
  const std::string body = R"({"sources": {"faces": [0], "weights": [1, 0, 0]}, "radius": 1.5})";
  const HttpResponse r = Post("/v1/models/torus:field", body);
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_THAT(r.body, HasSubstr(R"("vertices":[4,9,17])"));
  const auto merged = Parse<v1::DistanceFieldChunk>(r);
  EXPECT_EQ(merged.num_vertices(), 3);
  ASSERT_EQ(merged.distances_size(), 3);
  EXPECT_EQ(merged.distances(2), 0.75);
  ExpectError(Post("/v1/models/torus:field", body), 500, absl::StatusCode::kDataLoss,
              "one vertex per distance");
}

TEST_F(WebGatewayTest, MeshChunksAreMerged) {
  v1::MeshChunk c0, c1;
  for (auto* c : {&c0, &c1}) {
    c->set_num_vertices(4);
    c->set_num_faces(2);
    c->set_version(1);
  }
  for (double x : {0, 0, 0, 1, 0, 0, 0, 1, 0}) c0.add_positions(x);
  for (uint32_t v : {0, 1, 2}) c0.add_faces(v);
  c1.set_vertex_offset(3);
  c1.set_face_offset(1);
  for (double x : {1, 1, 0}) c1.add_positions(x);
  for (uint32_t v : {1, 3, 2}) c1.add_faces(v);
  EXPECT_CALL(*mock_, GetMesh).WillOnce([&](const v1::GetMeshRequest& request) {
    EXPECT_EQ(request.model().name(), "quad");
    EXPECT_EQ(request.model().version(), 1);
    return std::vector<v1::MeshChunk>{c0, c1};
  });
  const HttpResponse r = Get("/v1/models/quad/mesh", {{"version", "1"}});
  ASSERT_EQ(r.status, 200) << r.body;
  const auto mesh = Parse<v1::MeshChunk>(r);
  EXPECT_EQ(mesh.positions_size(), 12);
  EXPECT_EQ(mesh.faces_size(), 6);
  EXPECT_EQ(mesh.faces(4), 3u);
  EXPECT_EQ(mesh.vertex_offset(), 0u);
}

TEST_F(WebGatewayTest, MatrixAndTriangulation) {
  v1::MatrixBlock b0, b1;
  for (auto* b : {&b0, &b1}) {
    b->set_rows(1);
    b->set_num_targets(2);
  }
  b0.add_values(1);
  b0.add_values(2);
  b1.set_row_offset(1);
  b1.add_values(3);
  b1.add_values(4);
  EXPECT_CALL(*mock_, Matrix).WillOnce(Return(std::vector<v1::MatrixBlock>{b0, b1}));
  const auto matrix = Parse<v1::MatrixBlock>(Post("/v1/models/t:matrix", "{}"));
  EXPECT_EQ(matrix.rows(), 2);
  EXPECT_EQ(matrix.values(3), 4);

  v1::TriangulationResponse t;
  t.add_vertex_triangles(-1);
  t.add_triangle_corners(0);
  EXPECT_CALL(*mock_, GetTriangulation).WillOnce([&](const v1::GetTriangulationRequest& r) {
    EXPECT_EQ(r.model().name(), "t");
    return t;
  });
  const HttpResponse r = Get("/v1/models/t/triangulation");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(Parse<v1::TriangulationResponse>(r).vertex_triangles(0), -1);
}

// The model a request names ("" for a request without one).
template <class Request>
std::string ModelName(const Request& request) {
  if constexpr (requires { request.model(); }) {
    return request.model().name();
  } else {
    return "";
  }
}

// Every call of GEODEX_CLIENT_RPCS but those with a GET route answers POST
// /v1/models/{name}:<verb> (an empty answer, or no chunks, is 200) and
// refuses GET there.
TEST_F(WebGatewayTest, EveryCallWithoutAGetRouteHasAPostRoute) {
  const std::vector<std::string> post = PostRpcs();
  for (const char* rpc : {"Distance", "Path", "Locate", "Matrix", "DistanceField"}) {
    EXPECT_THAT(post, ::testing::Contains(rpc));
  }
  for (const char* rpc : {"ListModels", "GetModel", "GetMesh", "GetTriangulation"}) {
    EXPECT_THAT(post, ::testing::Not(::testing::Contains(rpc)));
  }
  EXPECT_EQ(PostVerb("DistanceField"), "field");
  EXPECT_EQ(PostVerb("Distance"), "distance");
  int routed = 0;
#define GEODEX_TEST_POST_ROUTE(Name, Request, Result)                          \
  if (std::find(post.begin(), post.end(), #Name) != post.end()) {              \
    EXPECT_CALL(*mock_, Name).WillOnce([](const Request& request) -> Result {  \
      EXPECT_EQ(ModelName(request), "t");                                      \
      return Result{};                                                         \
    });                                                                        \
    const std::string path = "/v1/models/t:" + PostVerb(#Name);                \
    const HttpResponse r = Post(path, "{}");                                   \
    EXPECT_EQ(r.status, 200) << #Name << ": " << r.body;                       \
    EXPECT_EQ(r.content_type, "application/json");                             \
    ExpectError(Get(path), 405, absl::StatusCode::kUnimplemented, "use POST"); \
    ++routed;                                                                  \
  }
  GEODEX_CLIENT_RPCS(GEODEX_TEST_POST_ROUTE)
#undef GEODEX_TEST_POST_ROUTE
  EXPECT_EQ(routed, static_cast<int>(post.size()));
  ExpectError(Post("/v1/models/t:getmodel", "{}"), 404, absl::StatusCode::kNotFound,
              "no such method");
}

// A chunk type of no query, for the generic merge: parallel arrays, their
// count and a version.
class MergeChunksTest : public ::testing::Test {
 protected:
  MergeChunksTest() {
    google::protobuf::FileDescriptorProto file;
    EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(
        R"pb(
          name: "merge_chunks_test.proto"
          package: "test"
          syntax: "proto3"
          message_type {
            name: "Chunk"
            field { name: "ids" number: 1 label: LABEL_REPEATED type: TYPE_INT32 }
            field { name: "values" number: 2 label: LABEL_REPEATED type: TYPE_DOUBLE }
            field { name: "num_entries" number: 3 label: LABEL_OPTIONAL type: TYPE_INT64 }
            field { name: "version" number: 4 label: LABEL_OPTIONAL type: TYPE_INT64 }
          })pb",
        &file));
    EXPECT_NE(pool_.BuildFile(file), nullptr);
    prototype_ = factory_.GetPrototype(pool_.FindMessageTypeByName("test.Chunk"));
  }
  std::unique_ptr<google::protobuf::Message> Chunk(const std::string& text) {
    std::unique_ptr<google::protobuf::Message> chunk(prototype_->New());
    EXPECT_TRUE(google::protobuf::TextFormat::ParseFromString(text, chunk.get())) << text;
    return chunk;
  }
  absl::Status Merge(const std::vector<std::string>& texts, google::protobuf::Message* out) {
    std::vector<std::unique_ptr<google::protobuf::Message>> owned;
    std::vector<const google::protobuf::Message*> chunks;
    for (const std::string& text : texts) {
      owned.push_back(Chunk(text));
      chunks.push_back(owned.back().get());
    }
    return MergeChunks(chunks, out);
  }

  google::protobuf::DescriptorPool pool_;
  google::protobuf::DynamicMessageFactory factory_;
  const google::protobuf::Message* prototype_ = nullptr;
};

TEST_F(MergeChunksTest, ConcatenatesTheArraysAndKeepsTheTotals) {
  std::unique_ptr<google::protobuf::Message> out(prototype_->New());
  ASSERT_TRUE(Merge({"ids: [4, 9] values: [0.5, 1.25] num_entries: 3 version: 2",
                     "ids: [17] values: [0.75] num_entries: 3 version: 2"},
                    out.get())
                  .ok());
  const auto want = Chunk("ids: [4, 9, 17] values: [0.5, 1.25, 0.75] num_entries: 3 version: 2");
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(*out, *want))
      << out->DebugString();
  ASSERT_TRUE(Merge({}, out.get()).ok());
  EXPECT_EQ(out->ByteSizeLong(), 0u);
}

TEST_F(MergeChunksTest, RefusesChunksThatDoNotTile) {
  std::unique_ptr<google::protobuf::Message> out(prototype_->New());
  absl::Status s = Merge({"ids: [4] values: [0.5] num_entries: 2 version: 2",
                          "ids: [9] values: [1] num_entries: 2 version: 3"},
                         out.get());
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("the server's Chunk chunks disagree"));
  s = Merge({"ids: [4, 9] values: [0.5] num_entries: 2"}, out.get());
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("arrays of different lengths"));
  s = Merge({"ids: [4] values: [0.5] num_entries: 2"}, out.get());
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("do not add up to its num_entries"));
}

TEST_F(WebGatewayTest, ExceptionsBecomeInternalErrors) {
  EXPECT_CALL(*mock_, ListModels)
      .WillOnce([](const v1::ListModelsRequest&) -> absl::StatusOr<v1::ListModelsResponse> {
        throw std::runtime_error("boom");
      });
  ExpectError(Get("/v1/models"), 500, absl::StatusCode::kInternal, "boom");
}

TEST(MeshToJson, IsProtobufsJsonByteForByte) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(-3, 3);
  v1::MeshChunk mesh;
  mesh.set_num_vertices(4000000000u);
  mesh.set_num_faces(7);
  mesh.set_version(-12345678901234);
  mesh.set_vertex_offset(3);
  mesh.set_face_offset(9);
  for (int i = 0; i < 20000; ++i) mesh.add_positions(uniform(rng));
  for (int e = -320; e <= 308; e += 7) mesh.add_positions(std::ldexp(1.0, e / 3) * 1.1);
  for (double x : {0.0, -0.0, 1.0, -2.0, 0.1, 1e21, 1e-7, 123456789012345680.0, 5e-324,
                   std::numeric_limits<double>::max(), std::numeric_limits<double>::infinity(),
                   -std::numeric_limits<double>::infinity()}) {
    mesh.add_positions(x);
  }
  for (uint32_t v : {0u, 1u, 4294967295u, 65536u}) mesh.add_faces(v);
  std::string expected;
  google::protobuf::util::JsonPrintOptions options;
  options.always_print_primitive_fields = true;
  ASSERT_TRUE(google::protobuf::util::MessageToJsonString(mesh, &expected, options).ok());
  EXPECT_EQ(MeshToJson(mesh), expected);
  v1::MeshChunk empty;
  expected.clear();  // MessageToJsonString appends
  ASSERT_TRUE(google::protobuf::util::MessageToJsonString(empty, &expected, options).ok());
  EXPECT_EQ(MeshToJson(empty), expected);
}

TEST(LoadWebAssets, NeedsEveryFile) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("geodex_web_assets_" + std::to_string(getpid())))
          .string();
  std::filesystem::create_directories(dir);
  for (const std::string& name : WebAssetNames()) {
    std::ofstream(dir + "/" + name) << "contents of " << name;
  }
  absl::StatusOr<WebAssets> assets = LoadWebAssets(dir);
  ASSERT_TRUE(assets.ok()) << assets.status();
  EXPECT_EQ(assets->at("/viewer.js").content_type, "application/javascript; charset=utf-8");
  EXPECT_EQ(assets->at("/three.min.js").body, "contents of three.min.js");
  std::filesystem::remove(dir + "/three.min.js");
  assets = LoadWebAssets(dir);
  EXPECT_EQ(assets.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(assets.status().message(), HasSubstr("three.min.js"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace geodex::client::cli
