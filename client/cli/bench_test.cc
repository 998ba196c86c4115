// The pairs `geodex bench` draws: uniform ones, and near ones at a given
// straight-line distance on one sheet of the surface.

#include "client/cli/bench.h"

#include <cmath>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client::cli {
namespace {

// An n x n grid of unit squares (two triangles each) in the plane z, its
// vertex ids from `first`.
void AddGrid(int n, double z, Mesh* mesh) {
  const uint32_t first = static_cast<uint32_t>(mesh->positions.size());
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) mesh->positions.push_back({1.0 * i, 1.0 * j, z});
  }
  auto id = [&](int i, int j) { return first + static_cast<uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      mesh->faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh->faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
}

Position At(const Mesh& mesh, const SurfacePoint& p) {
  Position x = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) x[c] += p.w[k] * mesh.positions[mesh.faces[p.face][k]][c];
  }
  return x;
}

double Distance(const Position& a, const Position& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

void ExpectValid(const SurfacePoint& p, size_t num_faces) {
  EXPECT_GE(p.face, 0);
  EXPECT_LT(static_cast<size_t>(p.face), num_faces);
  for (double w : p.w) EXPECT_GE(w, 0);
  EXPECT_NEAR(p.w[0] + p.w[1] + p.w[2], 1, 1e-12);
}

TEST(BenchPairs, ScaleLengthIsTheEngines) {
  Mesh mesh;
  AddGrid(10, 0, &mesh);  // area 100
  EXPECT_NEAR(ScaleLength(mesh, 50), std::sqrt(2 * 100 / (std::sqrt(3.0) * 50)), 1e-12);
  EXPECT_EQ(ScaleLength(mesh, 0), 0);
  EXPECT_EQ(ScaleLength(Mesh{}, 10), 0);
}

TEST(BenchPairs, NearPairsLieBetweenTheirBoundsOnOneSheet) {
  // Two parallel sheets 0.5 apart, not connected: a pair across them would
  // be 0.5 apart in a straight line but infinitely far on the surface.
  Mesh mesh;
  AddGrid(20, 0, &mesh);
  AddGrid(20, 0.5, &mesh);
  const size_t half = mesh.faces.size() / 2;
  const std::vector<PointPair> pairs = DrawNearPairs(mesh, 1.5, 4.5, 2000, 7);
  ASSERT_EQ(pairs.size(), 2000u);
  double shortest = 1e9, longest = 0;
  size_t upper = 0;
  for (const PointPair& pair : pairs) {
    ExpectValid(pair.a, mesh.faces.size());
    ExpectValid(pair.b, mesh.faces.size());
    EXPECT_EQ(static_cast<size_t>(pair.a.face) < half, static_cast<size_t>(pair.b.face) < half);
    const double d = Distance(At(mesh, pair.a), At(mesh, pair.b));
    shortest = std::min(shortest, d);
    longest = std::max(longest, d);
    upper += static_cast<size_t>(pair.a.face) >= half;
  }
  EXPECT_GE(shortest, 1.5);
  EXPECT_LE(longest, 4.5);
  // The whole range is drawn, from both sheets.
  EXPECT_LT(shortest, 1.7);
  EXPECT_GT(longest, 4.2);
  EXPECT_GT(upper, 800u);
  EXPECT_LT(upper, 1200u);
  // The same seed, the same pairs; another seed, others.
  const std::vector<PointPair> again = DrawNearPairs(mesh, 1.5, 4.5, 2000, 7);
  const std::vector<PointPair> other = DrawNearPairs(mesh, 1.5, 4.5, 2000, 8);
  EXPECT_EQ(again[99].a.face, pairs[99].a.face);
  EXPECT_EQ(again[99].b.w, pairs[99].b.w);
  EXPECT_NE(other[99].b.w, pairs[99].b.w);
}

TEST(BenchPairs, NoNearPairsOnAMeshSmallerThanTheirDistance) {
  Mesh mesh;
  AddGrid(2, 0, &mesh);  // diagonal 2.83
  EXPECT_TRUE(DrawNearPairs(mesh, 3, 9, 100, 1).empty());
  EXPECT_EQ(DrawNearPairs(mesh, 0.5, 1, 100, 1).size(), 100u);
  EXPECT_TRUE(DrawNearPairs(Mesh{}, 0.5, 1, 100, 1).empty());
}

TEST(BenchPairs, UniformPairsAreValidAndCoverTheFaces) {
  const std::vector<PointPair> pairs = RandomPairs(30, 3000, 3);
  ASSERT_EQ(pairs.size(), 3000u);
  std::vector<int> hits(30, 0);
  for (const PointPair& pair : pairs) {
    ExpectValid(pair.a, 30);
    ExpectValid(pair.b, 30);
    ++hits[pair.a.face];
  }
  for (int h : hits) EXPECT_GT(h, 50);
}

TEST(BenchPairs, AreaUniformPairsDrawFacesByArea) {
  // Two triangles, of areas 0.5 and 1.5: three times as many points in the
  // second.
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {4, 0, 0}, {4, 1, 0}};
  mesh.faces = {{0, 1, 2}, {1, 3, 4}};
  const std::vector<PointPair> pairs = AreaUniformPairs(mesh, 20000, 5);
  ASSERT_EQ(pairs.size(), 20000u);
  int first = 0;
  for (const PointPair& pair : pairs) {
    ExpectValid(pair.a, 2);
    ExpectValid(pair.b, 2);
    first += (pair.a.face == 0) + (pair.b.face == 0);
  }
  EXPECT_NEAR(first / 40000.0, 0.25, 0.01);
  EXPECT_TRUE(AreaUniformPairs(Mesh{}, 10, 1).empty());
}

}  // namespace
}  // namespace geodex::client::cli
