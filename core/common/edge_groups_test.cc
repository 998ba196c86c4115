#include "core/common/edge_groups.h"

#include <array>
#include <utility>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex {
namespace {

using ::testing::ElementsAre;

struct Edge {
  int64_t a, b;
  std::vector<int32_t> halfedges;
  bool operator==(const Edge&) const = default;
};

// The edges ForEachEdge visits for faces given three corners each.
std::vector<Edge> EdgesOf(const std::vector<std::array<int32_t, 3>>& faces) {
  auto ends = [&](int32_t h) {
    return std::pair<int32_t, int32_t>(faces[h / 3][h % 3], faces[h / 3][(h % 3 + 1) % 3]);
  };
  std::vector<Edge> edges;
  const absl::Status status =
      ForEachEdge(3 * static_cast<int32_t>(faces.size()), ends,
                  [&](std::span<const int32_t> group, int64_t a, int64_t b) {
                    edges.push_back({a, b, std::vector<int32_t>(group.begin(), group.end())});
                    return absl::OkStatus();
                  });
  EXPECT_TRUE(status.ok()) << status;
  return edges;
}

TEST(EdgeGroupsTest, GroupsHalfEdgesByUndirectedEdgeInOrder) {
  // Two triangles sharing edge (1, 2), run 1 -> 2 by face 0 and 2 -> 1 by face 1.
  EXPECT_THAT(EdgesOf({{0, 1, 2}, {2, 1, 3}}),
              ElementsAre(Edge{0, 1, {0}}, Edge{0, 2, {2}}, Edge{1, 2, {1, 3}}, Edge{1, 3, {4}},
                          Edge{2, 3, {5}}));
}

TEST(EdgeGroupsTest, KeepsEveryHalfEdgeOfANonManifoldEdge) {
  // Three faces on edge (0, 1), two of them running it the same way.
  const std::vector<Edge> edges = EdgesOf({{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  ASSERT_FALSE(edges.empty());
  EXPECT_EQ(edges[0], (Edge{0, 1, {0, 3, 6}}));
}

TEST(EdgeGroupsTest, StopsAtTheFirstError) {
  const std::vector<std::array<int32_t, 3>> faces = {{0, 1, 2}, {2, 1, 3}};
  auto ends = [&](int32_t h) {
    return std::pair<int32_t, int32_t>(faces[h / 3][h % 3], faces[h / 3][(h % 3 + 1) % 3]);
  };
  int visits = 0;
  const absl::Status status =
      ForEachEdge(6, ends, [&](std::span<const int32_t> group, int64_t, int64_t) {
        ++visits;
        return group.size() == 2 ? absl::DataLossError("shared") : absl::OkStatus();
      });
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_EQ(visits, 3);  // (0, 1), (0, 2), then (1, 2) fails
}

TEST(EdgeGroupsTest, NoHalfEdgesVisitsNothing) { EXPECT_TRUE(EdgesOf({}).empty()); }

}  // namespace
}  // namespace geodex
