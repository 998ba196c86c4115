// The gRPC connection against an in-process fake server: wire conversion,
// metadata, deadlines, retries, load balancing and streaming over real gRPC.

#include "client/grpc_connection.h"

#include <thread>

#include "client/fake_geodex_service_testing.h"
#include "geodex/client/client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client {
namespace {

using ::testing::ElementsAre;
using testing::FakeGeodexServer;
using ::testing::HasSubstr;

ConnectOptions FastRetries() {
  ConnectOptions options;
  options.deadline = absl::Seconds(10);
  options.retry.initial_backoff = absl::Milliseconds(1);
  options.retry.max_backoff = absl::Milliseconds(5);
  return options;
}

std::vector<PointPair> Pairs(size_t n) {
  std::vector<PointPair> pairs(n);
  for (size_t i = 0; i < n; ++i) {
    pairs[i].a = {static_cast<int32_t>(i % 100), {1, 0, 0}};
    pairs[i].b = {0, {1, 0, 0}};
  }
  return pairs;
}

TEST(NormalizeTarget, ListsOfIpLiteralsBecomeIpvSchemes) {
  EXPECT_EQ(*NormalizeTarget("localhost:50051"), "localhost:50051");
  EXPECT_EQ(*NormalizeTarget("dns:///geodex.svc:50051"), "dns:///geodex.svc:50051");
  EXPECT_EQ(*NormalizeTarget("10.0.0.1:1,10.0.0.2:2"), "ipv4:10.0.0.1:1,10.0.0.2:2");
  EXPECT_EQ(*NormalizeTarget("10.0.0.1:1, 10.0.0.2:2"), "ipv4:10.0.0.1:1,10.0.0.2:2");
  EXPECT_EQ(*NormalizeTarget("[::1]:1,[::1]:2"), "ipv6:[::1]:1,[::1]:2");
  EXPECT_EQ(*NormalizeTarget("ipv4:10.0.0.1:1,10.0.0.2:2"), "ipv4:10.0.0.1:1,10.0.0.2:2");
  EXPECT_EQ(NormalizeTarget("").status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(NormalizeTarget("a.example:1,b.example:2").status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(NormalizeTarget("10.0.0.1:1,[::1]:2").status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(NormalizeTarget("10.0.0.1,10.0.0.2").status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(Connect, BadTlsOptionsAreRejectedUpFront) {
  ConnectOptions options;
  options.tls.cert_file = "/nonexistent/cert.pem";
  EXPECT_EQ(Connect("localhost:1", options).status().code(), absl::StatusCode::kInvalidArgument);
  options.tls.key_file = "/nonexistent/key.pem";
  EXPECT_EQ(Connect("localhost:1", options).status().code(), absl::StatusCode::kNotFound);
  ConnectOptions ca;
  ca.tls.ca_file = "/nonexistent/ca.pem";
  EXPECT_EQ(Connect("localhost:1", ca).status().code(), absl::StatusCode::kNotFound);
  ConnectOptions token;
  token.bearer_token = "two\nlines";
  EXPECT_EQ(Connect("localhost:1", token).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(GrpcClient, AllMethodsOverTheWire) {
  FakeGeodexServer server;
  absl::StatusOr<Client> client = Connect(server.address(), FastRetries());
  ASSERT_TRUE(client.ok()) << client.status();

  absl::StatusOr<std::vector<ModelInfo>> models = client->ListModels();
  ASSERT_TRUE(models.ok()) << models.status();
  ASSERT_EQ(models->size(), 2u);
  EXPECT_EQ((*models)[0].name, "fake");
  EXPECT_EQ((*models)[0].num_faces, 100);
  EXPECT_EQ((*models)[1].state, ModelInfo::State::kLoading);

  absl::StatusOr<std::vector<double>> d =
      client->Distance("fake", std::vector<PointPair>{{{3, {1, 0, 0}}, {1, {0, 1, 0}}}});
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_THAT(*d, ElementsAre(2 + 2));

  std::vector<SurfacePoint> sources = {{0, {1, 0, 0}}, {5, {1, 0, 0}}, {9, {1, 0, 0}}};
  absl::StatusOr<DistanceMatrix> m = client->Matrix("fake", sources, {{2, {1, 0, 0}}});
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_THAT(m->values, ElementsAre(2, 3, 7));

  absl::StatusOr<VertexDistances> field = client->DistanceField("fake", {{10, {1, 0, 0}}}, true);
  ASSERT_TRUE(field.ok()) << field.status();
  ASSERT_EQ(field->distances.size(), 60u);
  EXPECT_EQ(field->distances[0], 10);
  EXPECT_EQ(field->distances[59], 49);
  EXPECT_EQ(field->nearest_source[30], 0);

  absl::StatusOr<std::vector<GeodesicPath>> paths = client->Path("fake", Pairs(3));
  ASSERT_TRUE(paths.ok()) << paths.status();
  ASSERT_EQ(paths->size(), 3u);
  EXPECT_EQ((*paths)[2].length, 2);
  EXPECT_EQ((*paths)[2].positions[0], (Position{2, 0, 0}));

  absl::StatusOr<std::vector<LocatedPoint>> located =
      client->Locate("fake", std::vector<Position>{{4.5, -2, 0}});
  ASSERT_TRUE(located.ok()) << located.status();
  EXPECT_EQ((*located)[0].point.face, 4);
  EXPECT_EQ((*located)[0].distance, 2);

  absl::StatusOr<Mesh> mesh = client->GetMesh({"fake", 1});  // in 10 chunks
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_EQ(mesh->version, 1);
  ASSERT_EQ(mesh->positions.size(), 60u);
  ASSERT_EQ(mesh->faces.size(), 100u);
  EXPECT_EQ(mesh->positions[59], (Position{59, 1, 0}));
  EXPECT_EQ(mesh->faces[99], (std::array<uint32_t, 3>{39, 40, 41}));
  EXPECT_EQ(client->GetMesh("nope").status().code(), absl::StatusCode::kNotFound);
}

// A request with default fields, naming model "fake" if it names one.
template <typename Request>
Request OfTheFakeModel() {
  Request request;
  if constexpr (requires(Request& r) { r.mutable_model(); }) {
    request.mutable_model()->set_name("fake");
  }
  return request;
}

// The fake serves every call of the proto's list: each, asked of model
// "fake", answers; none is UNIMPLEMENTED (a call added to geodex.proto and
// not to the fake fails here).
TEST(GrpcClient, TheFakeServesEveryCallOfTheList) {
  FakeGeodexServer server;
  absl::StatusOr<std::shared_ptr<GeodexConnection>> connection =
      MakeGrpcConnectionNoRetry(server.address(), FastRetries());
  ASSERT_TRUE(connection.ok()) << connection.status();
  int calls = 0;
#define GEODEX_TEST_CALL(Name, Request, Result)                                          \
  {                                                                                      \
    const absl::Status status = (*connection)->Name(OfTheFakeModel<Request>()).status(); \
    EXPECT_NE(status.code(), absl::StatusCode::kUnimplemented) << #Name << ": " << status; \
    ++calls;                                                                             \
  }
  GEODEX_CLIENT_RPCS(GEODEX_TEST_CALL)
#undef GEODEX_TEST_CALL
  EXPECT_GE(calls, 10);
  std::unique_ptr<DistanceStream> stream = (*connection)->StreamDistances(StreamOptions{});
  v1::DistanceBatch batch;
  batch.mutable_model()->set_name("fake");
  ASSERT_TRUE(stream->Write(batch));
  stream->WritesDone();
  v1::DistanceResult result;
  EXPECT_TRUE(stream->Read(&result));
  EXPECT_TRUE(stream->Finish().ok());
}

// Vertex ids and the triangulation over the wire, against the fake's closed
// forms.
TEST(GrpcClient, VertexIdsAndTriangulationOverTheWire) {
  FakeGeodexServer server;
  absl::StatusOr<Client> client = Connect(server.address(), FastRetries());
  ASSERT_TRUE(client.ok()) << client.status();
  // Vertex 7 is (face 5, w (0, 0, 1)); vertex 1 is (face 0, w (0, 1, 0)).
  absl::StatusOr<std::vector<double>> d = client->Distance(
      "fake", std::vector<PointPair>{{SurfacePoint::Vertex(7), {3, {0, 0, 1}}},
                                     {SurfacePoint::Vertex(1), SurfacePoint::Vertex(7)}});
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_THAT(*d, ElementsAre(2, 5 + 2));
  EXPECT_EQ(client->Distance("fake", std::vector<PointPair>{{SurfacePoint::Vertex(60),
                                                              SurfacePoint::Vertex(0)}})
                .status()
                .code(),
            absl::StatusCode::kOutOfRange);

  absl::StatusOr<std::shared_ptr<GeodexConnection>> connection =
      MakeGrpcConnectionNoRetry(server.address(), FastRetries());
  ASSERT_TRUE(connection.ok()) << connection.status();
  v1::GetTriangulationRequest request;
  request.mutable_model()->set_name("fake");
  absl::StatusOr<v1::TriangulationResponse> t = (*connection)->GetTriangulation(request);
  ASSERT_TRUE(t.ok()) << t.status();
  EXPECT_EQ(t->sample_vertices_size(), 10);
  EXPECT_EQ(t->sample_vertices(3), 18);
  EXPECT_EQ(t->sample_points().faces(3), 16);
  EXPECT_EQ(t->triangle_corners_size(), 3 * 16);
  EXPECT_EQ(t->vertex_triangles(20), 4);
}

TEST(GrpcClient, ManyPairsStreamedInOrder) {
  FakeGeodexServer server;
  ConnectOptions options = FastRetries();
  options.batch_size = 997;
  absl::StatusOr<Client> client = Connect(server.address(), options);
  ASSERT_TRUE(client.ok());
  const std::vector<PointPair> pairs = Pairs(100000);
  absl::StatusOr<std::vector<double>> d = client->Distance("fake", pairs);
  ASSERT_TRUE(d.ok()) << d.status();
  ASSERT_EQ(d->size(), pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) ASSERT_EQ((*d)[i], i % 100) << i;
}

TEST(GrpcClient, ServerErrorsKeepCodeAndMessage) {
  FakeGeodexServer server;
  ConnectOptions options = FastRetries();
  options.batch_size = 10;
  absl::StatusOr<Client> client = Connect(server.address(), options);
  ASSERT_TRUE(client.ok());
  EXPECT_EQ(client->GetModel("nope").status(), absl::NotFoundError("model 'nope' not found"));
  // One batch: the unary call's error as is.
  std::vector<PointPair> pairs = Pairs(5);
  pairs[3].b.face = 1000;
  EXPECT_EQ(client->Distance("fake", pairs).status(),
            absl::OutOfRangeError("b[3]: face 1000 is past the end (100 faces)"));
  // Streamed: the batch's error, located in the input.
  pairs = Pairs(50);
  pairs[23].a.w = {0.5, 0.5, 0.5};
  EXPECT_EQ(client->Distance("fake", pairs).status(),
            absl::InvalidArgumentError("pairs [20, 30): a[3]: weights sum to 1.5"));
  EXPECT_EQ(client->Distance("nope", pairs).status(),
            absl::NotFoundError("pairs [0, 10): model 'nope' not found"));
}

TEST(GrpcClient, UnavailableIsRetriedThenSucceeds) {
  FakeGeodexServer server;
  absl::StatusOr<Client> client = Connect(server.address(), FastRetries());
  ASSERT_TRUE(client.ok());
  ASSERT_TRUE(client->ListModels().ok());  // connected
  const int64_t before = server.service().calls();
  server.service().FailNext(2);
  ASSERT_TRUE(client->GetModel("fake").ok());
  EXPECT_EQ(server.service().calls() - before, 3);
}

TEST(GrpcClient, ModelLoadingIsRetriedAndReported) {
  FakeGeodexServer server;
  absl::StatusOr<Client> client = Connect(server.address(), FastRetries());
  ASSERT_TRUE(client.ok());
  absl::Status status = client->GetModel("loading").status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(status.message(), "model 'loading' is loading (gave up after 4 attempts)");
}

TEST(GrpcClient, NoServerIsUnavailable) {
  int port;
  {
    FakeGeodexServer gone;  // a port that was free a moment ago
    port = std::stoi(gone.address().substr(gone.address().rfind(':') + 1));
  }
  ConnectOptions options = FastRetries();
  options.retry.max_attempts = 2;
  absl::StatusOr<Client> client = Connect("127.0.0.1:" + std::to_string(port), options);
  ASSERT_TRUE(client.ok());
  absl::Status status = client->ListModels().status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(status.message()), HasSubstr("gave up after 2 attempts"));
}

TEST(GrpcClient, DeadlineExceededIsNotRetried) {
  FakeGeodexServer server;
  ConnectOptions options = FastRetries();
  options.deadline = absl::Milliseconds(100);
  absl::StatusOr<Client> client = Connect(server.address(), options);
  ASSERT_TRUE(client.ok());
  server.service().SetDelay(absl::Milliseconds(400));
  const int64_t before = server.service().calls();
  EXPECT_EQ(client->ListModels().status().code(), absl::StatusCode::kDeadlineExceeded);
  absl::SleepFor(absl::Milliseconds(500));
  EXPECT_EQ(server.service().calls() - before, 1);
}

TEST(GrpcClient, BearerTokenIsSentAsMetadataOnPlaintext) {
  FakeGeodexServer server;
  ConnectOptions options = FastRetries();
  options.bearer_token = "s3cret";
  absl::StatusOr<Client> client = Connect(server.address(), options);
  ASSERT_TRUE(client.ok());
  ASSERT_TRUE(client->ListModels().ok());
  EXPECT_EQ(server.service().last_authorization(), "Bearer s3cret");
  ASSERT_TRUE(client->Distance("fake", Pairs(5000)).ok());  // streams carry it too
  EXPECT_EQ(server.service().last_authorization(), "Bearer s3cret");
}

TEST(GrpcClient, RoundRobinOverAnAddressList) {
  FakeGeodexServer one, two;
  absl::StatusOr<Client> client = Connect(one.address() + "," + two.address(), FastRetries());
  ASSERT_TRUE(client.ok()) << client.status();
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(client->ListModels().ok());
  EXPECT_GE(one.service().calls(), 5);
  EXPECT_GE(two.service().calls(), 5);
  EXPECT_EQ(one.service().calls() + two.service().calls(), 20);
}

TEST(GrpcClient, SessionOverTheWire) {
  FakeGeodexServer server;
  absl::StatusOr<Client> client = Connect(server.address(), FastRetries());
  ASSERT_TRUE(client.ok());
  DistanceSession session = client->OpenDistanceSession("fake");
  std::vector<DistanceBatchResult> results;
  std::thread reader([&] {
    while (std::optional<DistanceBatchResult> r = session.Read()) results.push_back(*r);
  });
  const std::vector<PointPair> pairs = Pairs(100);
  for (int k = 0; k < 10; ++k) {
    ASSERT_TRUE(session.Send(absl::MakeConstSpan(pairs).subspan(10 * k, 10)).ok());
  }
  std::vector<PointPair> bad = Pairs(2);
  bad[1].a.face = -1;
  ASSERT_TRUE(session.Send(bad).ok());
  session.CloseSend();
  reader.join();
  EXPECT_TRUE(session.Finish().ok());
  ASSERT_EQ(results.size(), 11u);
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(results[k].batch_id, static_cast<uint64_t>(k));
    ASSERT_TRUE(results[k].status.ok());
    EXPECT_EQ(results[k].distances[9], 10 * k + 9);
  }
  EXPECT_EQ(results[10].status.code(), absl::StatusCode::kOutOfRange);
}

TEST(GrpcClient, AbandonedSessionIsCancelledCleanly) {
  FakeGeodexServer server;
  absl::StatusOr<Client> client = Connect(server.address(), FastRetries());
  ASSERT_TRUE(client.ok());
  {
    DistanceSession session = client->OpenDistanceSession("fake");
    ASSERT_TRUE(session.Send(Pairs(3)).ok());
  }  // destroyed without CloseSend/Finish
  EXPECT_TRUE(client->ListModels().ok());
}

}  // namespace
}  // namespace geodex::client
