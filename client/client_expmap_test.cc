// Client::ExpMap: the request it sends and how it assembles the chunks.

#include <limits>
#include <vector>

#include "geodex/client/client.h"
#include "geodex/client/mocks/mock_geodex_connection.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client {
namespace {

using ::testing::_;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Return;

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
  absl::StatusOr<ExpMap> map = client.ExpMap("torus", {0, {1, 0, 0}}, {.radius = 1});
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_TRUE(map->vertices.empty());
}

TEST(ClientExpMap, BadRadiusIsRejectedBeforeAnyCall) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, ExpMap).Times(0);
  Client client(mock);
  for (double radius : {0.0, -1.0, std::numeric_limits<double>::infinity(),
                        std::numeric_limits<double>::quiet_NaN()}) {
    absl::StatusOr<ExpMap> map = client.ExpMap("torus", {0, {1, 0, 0}}, {.radius = radius});
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
    EXPECT_EQ(client.ExpMap("torus", {0, {1, 0, 0}}, {.radius = 1}).status().code(),
              absl::StatusCode::kDataLoss)
        << i;
  }
}

TEST(ClientExpMap, ServerErrorsPassThrough) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, ExpMap(_)).WillOnce(Return(absl::NotFoundError("no model 'x'")));
  Client client(mock);
  EXPECT_EQ(client.ExpMap("x", {0, {1, 0, 0}}, {.radius = 1}).status().code(),
            absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace geodex::client
