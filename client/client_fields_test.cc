// The Client calls assembled from streamed chunks (client_fields.cc): the
// requests they send, how they assemble the chunks, and the chunks they
// refuse as DATA_LOSS.

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "client/fake_geodex_service_testing.h"
#include "geodex/client/client.h"
#include "geodex/client/mocks/mock_geodex_connection.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Return;

TEST(ClientDistanceField, ChunksAreAssembled) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, DistanceField).WillOnce([](const v1::DistanceFieldRequest& r) {
    EXPECT_TRUE(r.with_nearest_source());
    std::vector<v1::DistanceFieldChunk> chunks(2);
    chunks[0].set_vertex_offset(3);
    chunks[0].set_num_vertices(5);
    chunks[0].add_distances(3);
    chunks[0].add_distances(std::numeric_limits<double>::infinity());
    chunks[0].add_nearest_source(1);
    chunks[0].add_nearest_source(-1);
    chunks[1].set_vertex_offset(0);
    chunks[1].set_num_vertices(5);
    for (double d : {0, 1, 2}) {
      chunks[1].add_distances(d);
      chunks[1].add_nearest_source(0);
    }
    return chunks;
  });
  Client client(mock);
  absl::StatusOr<VertexDistances> field =
      client.DistanceField("torus", std::vector<SurfacePoint>(2), true);
  ASSERT_TRUE(field.ok()) << field.status();
  EXPECT_THAT(field->distances, ElementsAre(0, 1, 2, 3, std::numeric_limits<double>::infinity()));
  EXPECT_THAT(field->nearest_source, ElementsAre(0, 0, 0, 1, -1));
}

TEST(ClientDistanceField, GapIsDataLoss) {
  auto mock = std::make_shared<MockGeodexConnection>();
  v1::DistanceFieldChunk chunk;
  chunk.set_vertex_offset(0);
  chunk.set_num_vertices(4);
  chunk.add_distances(0);
  EXPECT_CALL(*mock, DistanceField).WillOnce(Return(std::vector<v1::DistanceFieldChunk>{chunk}));
  Client client(mock);
  EXPECT_EQ(client.DistanceField("torus", std::vector<SurfacePoint>(1)).status().code(),
            absl::StatusCode::kDataLoss);
}

// A chunk of a field within a radius: entries (vertex, distance, nearest
// source) from `offset` of an answer of `total` entries.
v1::DistanceFieldChunk SparseChunk(int64_t offset, int64_t total,
                                   std::vector<std::array<double, 3>> entries) {
  v1::DistanceFieldChunk chunk;
  chunk.set_vertex_offset(offset);
  chunk.set_num_vertices(total);
  chunk.set_version(4);
  for (const auto& [vertex, distance, nearest] : entries) {
    chunk.add_vertices(static_cast<int32_t>(vertex));
    chunk.add_distances(distance);
    chunk.add_nearest_source(static_cast<int32_t>(nearest));
  }
  return chunk;
}

TEST(ClientDistanceFieldWithin, SendsTheRadiusAndAssemblesTheChunks) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, DistanceField).WillOnce([](const v1::DistanceFieldRequest& r) {
    EXPECT_EQ(r.radius(), 2.5);
    EXPECT_TRUE(r.with_nearest_source());
    EXPECT_EQ(r.sources().faces_size(), 2);
    return std::vector<v1::DistanceFieldChunk>{SparseChunk(0, 3, {{2, 0.5, 0}, {7, 2.5, 1}}),
                                               SparseChunk(2, 3, {{11, 1, 1}})};
  });
  Client client(mock);
  absl::StatusOr<VertexDistancesWithin> field = client.DistanceFieldWithin(
      "torus", std::vector<SurfacePoint>(2), {.radius = 2.5, .with_nearest_source = true});
  ASSERT_TRUE(field.ok()) << field.status();
  EXPECT_THAT(field->vertices, ElementsAre(2, 7, 11));
  EXPECT_THAT(field->distances, ElementsAre(0.5, 2.5, 1));
  EXPECT_THAT(field->nearest_source, ElementsAre(0, 1, 1));
  EXPECT_EQ(field->version, 4);
}

TEST(ClientDistanceFieldWithin, BadRadiiAreRefusedBeforeAnyCall) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, DistanceField).Times(0);
  Client client(mock);
  for (double radius : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity()}) {
    const absl::Status s =
        client.DistanceFieldWithin("torus", std::vector<SurfacePoint>(1), {.radius = radius})
            .status();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << radius;
    EXPECT_THAT(s.message(), HasSubstr("radius must be finite and > 0"));
  }
}

TEST(ClientDistanceFieldWithin, InconsistentChunksAreDataLoss) {
  const std::vector<std::vector<v1::DistanceFieldChunk>> bad = {
      {SparseChunk(0, 3, {{2, 0.5, 0}, {7, 2.5, 1}})},                                  // short
      {SparseChunk(0, 3, {{2, 0.5, 0}, {7, 2.5, 1}}), SparseChunk(1, 3, {{9, 1, 0}})},  // overlap
      {SparseChunk(0, 2, {{7, 0.5, 0}, {2, 2.5, 1}})},                                  // order
      {SparseChunk(0, 2, {{2, 0.5, 0}}), SparseChunk(1, 3, {{7, 1, 0}})},               // totals
  };
  for (const auto& chunks : bad) {
    auto mock = std::make_shared<MockGeodexConnection>();
    EXPECT_CALL(*mock, DistanceField).WillOnce(Return(chunks));
    Client client(mock);
    EXPECT_EQ(client.DistanceFieldWithin("torus", std::vector<SurfacePoint>(1), {.radius = 3})
                  .status()
                  .code(),
              absl::StatusCode::kDataLoss);
  }
  // A server older than radius fields answers with the whole field.
  v1::DistanceFieldChunk whole;
  whole.set_num_vertices(2);
  whole.add_distances(0);
  whole.add_distances(1);
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, DistanceField).WillOnce(Return(std::vector<v1::DistanceFieldChunk>{whole}));
  Client client(mock);
  const absl::Status s =
      client.DistanceFieldWithin("torus", std::vector<SurfacePoint>(1), {.radius = 3}).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("predates radius fields"));
}

// A mesh of 4 vertices (vertex v at (v, 10 v, 100 v)) and 3 faces in two
// chunks: vertices 0-2 and faces 0-1, then vertex 3 and face 2.
std::vector<v1::MeshChunk> TwoMeshChunks() {
  std::vector<v1::MeshChunk> chunks(2);
  for (v1::MeshChunk& chunk : chunks) {
    chunk.set_num_vertices(4);
    chunk.set_num_faces(3);
    chunk.set_version(7);
  }
  for (int v = 0; v < 3; ++v) {
    for (double c : {1.0 * v, 10.0 * v, 100.0 * v}) chunks[0].add_positions(c);
  }
  for (uint32_t id : {0, 1, 2, 0, 2, 3}) chunks[0].add_faces(id);
  chunks[1].set_vertex_offset(3);
  chunks[1].set_face_offset(2);
  for (double c : {3.0, 30.0, 300.0}) chunks[1].add_positions(c);
  for (uint32_t id : {3, 1, 0}) chunks[1].add_faces(id);
  return chunks;
}

TEST(ClientMesh, ChunksAreAssembled) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, GetMesh).WillOnce([](const v1::GetMeshRequest& r) {
    EXPECT_EQ(r.model().name(), "torus");
    EXPECT_EQ(r.model().version(), 7);
    return TwoMeshChunks();
  });
  Client client(mock);
  absl::StatusOr<Mesh> mesh = client.GetMesh({"torus", 7});
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_EQ(mesh->version, 7);
  EXPECT_THAT(mesh->positions, ElementsAre(Position{0, 0, 0}, Position{1, 10, 100},
                                           Position{2, 20, 200}, Position{3, 30, 300}));
  using Face = std::array<uint32_t, 3>;
  EXPECT_THAT(mesh->faces, ElementsAre(Face{0, 1, 2}, Face{0, 2, 3}, Face{3, 1, 0}));
}

TEST(ClientMesh, ServerErrorsPassThroughAndNoModelIsInvalid) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, GetMesh).WillOnce(Return(absl::NotFoundError("unknown model 'nope'")));
  Client client(mock);
  EXPECT_EQ(client.GetMesh("nope").status(), absl::NotFoundError("unknown model 'nope'"));
  EXPECT_EQ(client.GetMesh("").status().code(), absl::StatusCode::kInvalidArgument);
}

// Every way the chunks can fail to be one mesh is DATA_LOSS, with a message
// that says what was wrong.
TEST(ClientMesh, MalformedChunksAreDataLoss) {
  struct Case {
    const char* name;
    std::function<void(std::vector<v1::MeshChunk>&)> spoil;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"no chunks", [](auto& c) { c.clear(); }, "no mesh chunks"},
      {"totals change", [](auto& c) { c[1].set_num_vertices(5); }, "chunk 1 is of a mesh of 5"},
      {"face total changes", [](auto& c) { c[1].set_num_faces(2); }, "chunk 1 is of a mesh"},
      {"version changes", [](auto& c) { c[1].set_version(8); }, "version 8"},
      {"gap", [](auto& c) { c[1].set_vertex_offset(4); }, "chunk 1 starts at vertex 4"},
      {"overlap", [](auto& c) { c[1].set_face_offset(1); },
       "and face 1, not at vertex 3 and face 2"},
      {"out of order", [](auto& c) { std::swap(c[0], c[1]); },
       "chunk 0 starts at vertex 3 and face 2"},
      {"repeated", [](auto& c) { c[1] = c[0]; }, "chunk 1 starts at vertex 0"},
      {"coordinates not in threes", [](auto& c) { c[1].add_positions(1); }, "multiples of 3"},
      {"face ids not in threes", [](auto& c) { c[1].add_faces(1); }, "multiples of 3"},
      {"missing vertices", [](auto& c) { c[1].clear_positions(); },
       "sent 3 of 4 mesh vertices and 3 of 3 faces"},
      {"missing chunk", [](auto& c) { c.pop_back(); }, "sent 3 of 4 mesh vertices and 2 of 3"},
      {"past the end",
       [](auto& c) {
         for (auto& chunk : c) chunk.set_num_faces(1);
       },
       "past the end of the mesh: to vertex 3 of 4 and face 2 of 1"},
      {"vertex id past the end", [](auto& c) { c[1].set_faces(1, 4); },
       "mesh face 2 names vertex 4, past the end (4 vertices)"},
      {"another version than pinned",
       [](auto& c) {
         for (auto& chunk : c) chunk.set_version(6);
       },
       "mesh of version 6 when version 7 was asked for"},
  };
  for (const Case& test : cases) {
    auto mock = std::make_shared<MockGeodexConnection>();
    std::vector<v1::MeshChunk> chunks = TwoMeshChunks();
    test.spoil(chunks);
    EXPECT_CALL(*mock, GetMesh).WillOnce(Return(chunks));
    Client client(mock);
    const absl::Status status = client.GetMesh({"torus", 7}).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << test.name << ": " << status;
    EXPECT_THAT(status.message(), HasSubstr(test.message)) << test.name;
  }
}

// An exponential map query of `radius` and nothing else (a designated
// initializer would leave reference_direction to a warning).
ExpMapQuery WithinRadius(double radius) {
  ExpMapQuery query;
  query.radius = radius;
  return query;
}

// A chunk of entries (vertex, r, theta) of a map of `total` vertices.
v1::ExpMapChunk Chunk(std::vector<std::array<double, 3>> entries, int64_t total) {
  v1::ExpMapChunk chunk;
  chunk.set_num_vertices(total);
  chunk.set_version(7);
  for (const auto& [vertex, r, theta] : entries) {
    chunk.add_vertices(static_cast<int32_t>(vertex));
    chunk.add_r(r);
    chunk.add_theta(theta);
    chunk.add_u(r * std::cos(theta));
    chunk.add_v(r * std::sin(theta));
  }
  return chunk;
}

TEST(ClientExpMap, SendsTheQueryAndAssemblesTheChunks) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, ExpMap).WillOnce([](const v1::ExpMapRequest& r) {
    EXPECT_EQ(r.model().name(), "torus");
    EXPECT_EQ(r.center().faces_size(), 1);
    EXPECT_EQ(r.center().faces(0), 4);
    EXPECT_THAT(r.center().weights(), ElementsAre(0.25, 0.25, 0.5));
    EXPECT_EQ(r.radius(), 0.75);
    EXPECT_THAT(r.reference_direction().xyz(), ElementsAre(1, 2, 3));
    EXPECT_EQ(r.near_pairs(), v1::NEAR_PAIRS_EXACT);
    EXPECT_EQ(r.tolerance(), 0.01);
    return std::vector<v1::ExpMapChunk>{Chunk({{1, 0.5, 0.1}, {4, 0.25, -2}}, 3),
                                        Chunk({{9, 0.7, 3}}, 3)};
  });
  Client client(mock);
  ExpMapQuery query;
  query.radius = 0.75;
  query.reference_direction = Position{1, 2, 3};
  query.near_pairs = NearPairs::kExact;
  query.tolerance = 0.01;
  absl::StatusOr<ExpMap> map = client.ExpMap("torus", {4, {0.25, 0.25, 0.5}}, query);
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_THAT(map->vertices, ElementsAre(1, 4, 9));
  EXPECT_THAT(map->r, ElementsAre(0.5, 0.25, 0.7));
  EXPECT_THAT(map->theta, ElementsAre(0.1, -2, 3));
  EXPECT_DOUBLE_EQ(map->u[2], 0.7 * std::cos(3));
  EXPECT_DOUBLE_EQ(map->v[1], 0.25 * std::sin(-2));
  EXPECT_EQ(map->version, 7);
}

TEST(ClientExpMap, WithoutDirectionSendsNone) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, ExpMap).WillOnce([](const v1::ExpMapRequest& r) {
    EXPECT_FALSE(r.has_reference_direction());
    return std::vector<v1::ExpMapChunk>{Chunk({}, 0)};
  });
  Client client(mock);
  absl::StatusOr<ExpMap> map = client.ExpMap("torus", {0, {1, 0, 0}}, WithinRadius(1));
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_TRUE(map->vertices.empty());
}

TEST(ClientExpMap, BadRadiusIsRejectedBeforeAnyCall) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, ExpMap).Times(0);
  Client client(mock);
  for (double radius : {0.0, -1.0, std::numeric_limits<double>::infinity(),
                        std::numeric_limits<double>::quiet_NaN()}) {
    absl::StatusOr<ExpMap> map = client.ExpMap("torus", {0, {1, 0, 0}}, WithinRadius(radius));
    EXPECT_EQ(map.status().code(), absl::StatusCode::kInvalidArgument) << radius;
    EXPECT_THAT(map.status().message(), HasSubstr("radius"));
  }
}

TEST(ClientExpMap, InconsistentChunksAreDataLoss) {
  auto mock = std::make_shared<MockGeodexConnection>();
  v1::ExpMapChunk short_r = Chunk({{1, 0.5, 0.1}}, 1);
  short_r.clear_r();
  EXPECT_CALL(*mock, ExpMap)
      .WillOnce(Return(std::vector<v1::ExpMapChunk>{Chunk({{1, 0.5, 0.1}}, 2)}))  // missing
      .WillOnce(Return(std::vector<v1::ExpMapChunk>{Chunk({{4, 0.5, 0.1}}, 2),
                                                    Chunk({{2, 0.5, 0.1}}, 2)}))  // order
      .WillOnce(Return(std::vector<v1::ExpMapChunk>{short_r}))                    // sizes
      .WillOnce(Return(std::vector<v1::ExpMapChunk>{Chunk({{1, 0.5, 0.1}}, 1),
                                                    Chunk({{2, 0.5, 0.1}}, 1)}));  // extra
  Client client(mock);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(client.ExpMap("torus", {0, {1, 0, 0}}, WithinRadius(1)).status().code(),
              absl::StatusCode::kDataLoss)
        << i;
  }
}

TEST(ClientExpMap, ServerErrorsPassThrough) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, ExpMap).WillOnce(Return(absl::NotFoundError("no model 'x'")));
  Client client(mock);
  EXPECT_EQ(client.ExpMap("x", {0, {1, 0, 0}}, WithinRadius(1)).status().code(),
            absl::StatusCode::kNotFound);
}

// Over the wire, against the fake server's closed form of the map.
TEST(ClientExpMap, TheFakeServersMapOverTheWire) {
  testing::FakeGeodexServer server;
  absl::StatusOr<Client> client = Connect(server.address());
  ASSERT_TRUE(client.ok()) << client.status();
  absl::StatusOr<ExpMap> map = client->ExpMap("fake", {10, {1, 0, 0}}, WithinRadius(2));
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_THAT(map->vertices, ElementsAre(8, 9, 10, 11, 12));
  EXPECT_THAT(map->r, ElementsAre(2, 1, 0, 1, 2));
  EXPECT_DOUBLE_EQ(map->u[4], 2 * std::cos(0.5));
  // A vertex centre: vertex 12 is face 10 with weight 1 on its third corner.
  map = client->ExpMap("fake", SurfacePoint::Vertex(12), WithinRadius(1));
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_THAT(map->vertices, ElementsAre(9, 10, 11));
  EXPECT_EQ(client->ExpMap("fake", {10, {1, 0, 0}}, WithinRadius(-1)).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace geodex::client
