#include "core/query/engine/internal/paths/cut_bound.h"

#include <cmath>
#include <optional>
#include <random>

#include "core/mesh/generators.h"
#include "core/query/engine/internal/query_parts_testing.h"
#include "core/query/engine/query_scratch.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

using mesh::Vec3;

// The least sum over the segment, against a fine sampling of it.
TEST(TwoChordLengthTest, IsTheLeastSumOverTheSegment) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2, 2);
  auto point = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 p = point(), q = point(), a = point(), b = point();
    double least = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 20000; ++i) {
      const Vec3 x = a + (i / 20000.0) * (b - a);
      least = std::min(least, (p - x).norm() + (x - q).norm());
    }
    const double got = TwoChordLength(p, q, a, b);
    EXPECT_LE(got, least + 1e-12) << "trial " << trial;
    EXPECT_NEAR(got, least, 1e-6) << "trial " << trial;
    EXPECT_GE(got, (p - q).norm() - 1e-12) << "trial " << trial;
  }
  // A degenerate segment is its point.
  EXPECT_DOUBLE_EQ(TwoChordLength({0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {1, 1, 0}), 2 * std::sqrt(2.0));
}

// Interior points of faces a few rings apart, on a mesh's own index.
struct Pair {
  SurfacePoint p, q;
};
std::vector<Pair> NearPairs(const MeshView& view, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int32_t> face(0, static_cast<int32_t>(view.faces.size() / 3) - 1);
  std::uniform_real_distribution<double> w(0.05, 1);
  auto point = [&](int32_t f) {
    double a = w(rng), b = w(rng), c = w(rng);
    const double s = a + b + c;
    return SurfacePoint{f, {a / s, b / s, c / s}};
  };
  std::vector<Pair> pairs;
  for (int i = 0; i < count; ++i) {
    int32_t f = face(rng), g = f;
    // A random walk of a few faces from f.
    for (int step = 0; step < 3 + i % 12; ++step) {
      const int32_t twin = view.twins[3 * g + rng() % 3];
      if (twin >= 0) g = twin / 3;
    }
    if (g != f) pairs.push_back({point(f), point(g)});
  }
  return pairs;
}

// The bound never exceeds the exact distance and never falls below the
// chord, on closed curved surfaces and ones with saddles; on the sphere it
// is tighter than the chord for most pairs.
TEST(CutLowerBoundTest, LiesBetweenTheChordAndTheGeodesic) {
  const mesh::Mesh shapes[] = {mesh::gen::Sphere(3, 1.0), mesh::gen::Torus(40, 16, 1.0, 0.3),
                               mesh::gen::DoubleTorus(12, 1.0)};
  for (const mesh::Mesh& shape : shapes) {
    const testing::QueryParts parts(shape, 60);
    QueryScratch scratch;
    int tighter = 0, pairs = 0;
    for (const Pair& pair : NearPairs(parts.view, 300, 11)) {
      const std::optional<double> exact = parts.exact.NearDistance(pair.p, pair.q, &scratch);
      ASSERT_TRUE(exact.has_value());
      const double chord =
          (parts.view.PositionOf(pair.p) - parts.view.PositionOf(pair.q)).norm();
      const double bound =
          CutLowerBound(parts.view, pair.p, pair.q, 1.1 * *exact, 4096, &scratch.walks());
      EXPECT_LE(bound, *exact * (1 + 1e-12)) << shape.name() << " face " << pair.p.face;
      EXPECT_GE(bound, chord) << shape.name() << " face " << pair.p.face;
      tighter += bound > chord * (1 + 1e-9);
      ++pairs;
    }
    // The sphere bends everywhere; the others have flatter parts too.
    EXPECT_GT(tighter, &shape == &shapes[0] ? pairs / 2 : 0) << shape.name();
  }
}

// Across one sharp fold the two chords through the fold are the unfolded
// segment: the bound is the geodesic.
TEST(CutLowerBoundTest, IsExactAcrossOneFold) {
  const mesh::Mesh flat = mesh::gen::Grid(10, 10, 2, 2);
  const mesh::Mesh folded = mesh::gen::FoldedSheet(10, 10, 2, 2, 2.0);
  const testing::QueryParts parts(folded, 20);
  QueryScratch scratch;
  int exact = 0;
  for (int32_t f = 0; f + 23 < folded.num_faces(); f += 9) {
    const SurfacePoint a{f, {0.2, 0.3, 0.5}}, b{f + 23, {0.5, 0.25, 0.25}};
    const double want = (mesh::PositionOf(flat, a) - mesh::PositionOf(flat, b)).norm();
    const double bound = CutLowerBound(parts.view, a, b, 1.1 * want, 4096, &scratch.walks());
    EXPECT_LE(bound, want * (1 + 1e-12)) << "face " << f;
    exact += bound > want * (1 - 1e-9);
  }
  EXPECT_GT(exact, 0);
}

// Points in one face: the chord is the geodesic. A region held to a few
// faces gives the chord.
TEST(CutLowerBoundTest, OneFaceAndASmallBudgetGiveTheChord) {
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 60);
  QueryScratch scratch;
  const SurfacePoint a{7, {0.2, 0.3, 0.5}}, b{7, {0.6, 0.2, 0.2}};
  const double chord = (parts.view.PositionOf(a) - parts.view.PositionOf(b)).norm();
  EXPECT_EQ(CutLowerBound(parts.view, a, b, 10, 4096, &scratch.walks()), chord);
  for (const Pair& pair : NearPairs(parts.view, 20, 3)) {
    const double far_chord =
        (parts.view.PositionOf(pair.p) - parts.view.PositionOf(pair.q)).norm();
    EXPECT_EQ(CutLowerBound(parts.view, pair.p, pair.q, 10, 1, &scratch.walks()), far_chord);
  }
}

}  // namespace
}  // namespace geodex::query
