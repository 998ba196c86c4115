#include "core/geodesic/confined_geodesic.h"

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/generators.h"
#include "gtest/gtest.h"

namespace geodex::geodesic {
namespace {

using mesh::Mesh;
using mesh::SurfacePoint;
using mesh::Vec3;
namespace gen = mesh::gen;

// A grid of [0,1]^2 lifted to z = height(x, y).
Mesh HeightField(int n, const std::function<double(double, double)>& height) {
  const Mesh flat = gen::Grid(n, n, 1.0, 1.0);
  std::vector<Vec3> positions = flat.positions();
  for (Vec3& x : positions) x.z() = height(x.x(), x.y());
  return *Mesh::Create(std::move(positions), flat.faces(), "height field");
}

// An egg crate: a saddle at every other grid crossing of its bumps.
Mesh EggCrate() {
  return HeightField(36, [](double x, double y) {
    return 0.06 * std::sin(4 * std::numbers::pi * x) * std::sin(4 * std::numbers::pi * y);
  });
}

// One wide bump in the middle of the unit square.
Mesh Bump() {
  return HeightField(40, [](double x, double y) {
    const double r2 = (x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5);
    return 0.45 * std::exp(-r2 / (2 * 0.12 * 0.12));
  });
}

// Pseudo-random points of referenced faces: corners, edge points and
// interior points in turn.
std::vector<SurfacePoint> SomePoints(const Mesh& m, int count, uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int32_t> face(0, m.num_faces() - 1);
  std::uniform_real_distribution<double> unit(0.05, 0.95);
  std::vector<SurfacePoint> points;
  for (int i = 0; i < count; ++i) {
    SurfacePoint p{face(random), {0, 0, 0}};
    const double a = unit(random), b = unit(random);
    switch (i % 3) {
      case 0:
        p.w[i % 2] = 1;
        break;
      case 1:
        p.w[0] = a;
        p.w[1] = 1 - a;
        break;
      default:
        p.w = {a * b, (1 - a) * b, 1 - b};
    }
    points.push_back(p);
  }
  return points;
}

// The faces whose centroid lies within `radius` of the polyline `corners`
// (in the z = 0 projection).
std::vector<int32_t> FacesNearPolyline(const Mesh& m, const std::vector<Vec3>& corners,
                                       double radius) {
  std::vector<int32_t> faces;
  for (int32_t f = 0; f < m.num_faces(); ++f) {
    Vec3 c = Vec3::Zero();
    for (const int32_t v : m.face(f)) c += m.position(v) / 3;
    c.z() = 0;
    for (size_t i = 1; i < corners.size(); ++i) {
      const Vec3 a = corners[i - 1], ab = corners[i] - corners[i - 1];
      const double t = std::clamp((c - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      if ((a + t * ab - c).norm() < radius) {
        faces.push_back(f);
        break;
      }
    }
  }
  return faces;
}

// The face containing (x, y) of a height field over the unit square, as a
// surface point.
SurfacePoint PointAbove(const Mesh& m, double x, double y) {
  for (int32_t f = 0; f < m.num_faces(); ++f) {
    const auto& t = m.face(f);
    const Vec3 a = m.position(t[0]), b = m.position(t[1]), c = m.position(t[2]);
    const double det = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    const double wb = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / det;
    const double wc = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / det;
    if (wb >= 0 && wc >= 0 && wb + wc <= 1) return {f, {1 - wb - wc, wb, wc}};
  }
  ADD_FAILURE() << "no face above " << x << ", " << y;
  return {};
}

// Every pair of `points`: the confined distance equals the unconfined one,
// without seeds and with the neighbourhood of an unrelated point as the
// (wrong) seed. Returns how many calls had to grow their region.
int ExpectEqualsUnconfinedOnAllPairs(const Mesh& m, const std::vector<SurfacePoint>& points) {
  ExactGeodesicSolver reference(m);
  ConfinedGeodesicSolver confined(m);
  int grew = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_TRUE(reference.Propagate({points[i]}).ok());
    for (size_t j = 0; j < points.size(); ++j) {
      if (i == j) continue;
      const double want = reference.DistanceAt(points[j]);
      const absl::StatusOr<double> got = confined.Distance(points[i], points[j]);
      EXPECT_TRUE(got.ok()) << got.status();
      EXPECT_NEAR(*got, want, 1e-9 * want) << m.name() << " pair " << i << ", " << j;
      grew += confined.stats().rounds > 1;
      const int32_t wrong[] = {points[(i + j + 1) % points.size()].face};
      const absl::StatusOr<double> seeded = confined.Distance(points[i], points[j], wrong);
      EXPECT_TRUE(seeded.ok()) << seeded.status();
      EXPECT_NEAR(*seeded, want, 1e-9 * want) << m.name() << " seeded pair " << i << ", " << j;
    }
  }
  return grew;
}

TEST(ConfinedGeodesicTest, SphereEqualsUnconfined) {
  const Mesh m = gen::Sphere(3, 1.0);
  EXPECT_GT(ExpectEqualsUnconfinedOnAllPairs(m, SomePoints(m, 12, 1)), 0);
}

TEST(ConfinedGeodesicTest, TorusEqualsUnconfined) {
  const Mesh m = gen::Torus(48, 20, 1.0, 0.35);
  EXPECT_GT(ExpectEqualsUnconfinedOnAllPairs(m, SomePoints(m, 12, 2)), 0);
}

TEST(ConfinedGeodesicTest, EggCrateEqualsUnconfined) {
  const Mesh m = EggCrate();
  EXPECT_GT(ExpectEqualsUnconfinedOnAllPairs(m, SomePoints(m, 12, 3)), 0);
}

TEST(ConfinedGeodesicTest, SquareWithHoleEqualsUnconfined) {
  const Mesh m = gen::SquareWithHole(18, 1.0);
  EXPECT_GT(ExpectEqualsUnconfinedOnAllPairs(m, SomePoints(m, 12, 4)), 0);
}

// The first region holds only a path round the wrong side of the obstacle,
// longer than the true one: an answer not certified against the border would
// be that longer path's length.
void ExpectWrongCorridorIsOvercome(const Mesh& m, const SurfacePoint& p, const SurfacePoint& q,
                                   const std::vector<int32_t>& corridor) {
  ExactGeodesicSolver reference(m);
  ASSERT_TRUE(reference.Propagate({p}).ok());
  const double want = reference.DistanceAt(q);

  // The distance inside the first region (the corridor and its one-ring).
  std::vector<uint8_t> region(m.num_faces(), 0);
  for (const int32_t f : corridor) {
    for (const int32_t v : m.face(f)) {
      for (const int32_t o : m.Outgoing(v)) region[Mesh::FaceOf(o)] = 1;
    }
  }
  GeodesicOptions options;
  options.face_region = region;
  ASSERT_TRUE(reference.Propagate({p}, options).ok());
  const double inside = reference.DistanceAt(q);
  ASSERT_GT(inside, want * 1.02) << "the corridor must only hold a longer path";

  ConfinedGeodesicSolver confined(m);
  const absl::StatusOr<double> got = confined.Distance(p, q, corridor);
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_NEAR(*got, want, 1e-9 * want);
  EXPECT_GT(confined.stats().rounds, 1);
}

TEST(ConfinedGeodesicTest, CorridorOnTheWrongSideOfAHole) {
  const Mesh m = gen::SquareWithHole(24, 1.0);
  // p and q sit nearer the hole's lower side; the corridor goes over the top.
  const SurfacePoint p = PointAbove(m, 0.15, 0.42), q = PointAbove(m, 0.85, 0.42);
  const std::vector<int32_t> corridor = FacesNearPolyline(
      m, {Vec3(0.15, 0.42, 0), Vec3(0.25, 0.75, 0), Vec3(0.75, 0.75, 0), Vec3(0.85, 0.42, 0)},
      0.02);
  ExpectWrongCorridorIsOvercome(m, p, q, corridor);
}

TEST(ConfinedGeodesicTest, CorridorOverABumpThatTheGeodesicGoesAround) {
  const Mesh m = Bump();
  const SurfacePoint p = PointAbove(m, 0.2, 0.5), q = PointAbove(m, 0.8, 0.5);
  const std::vector<int32_t> corridor =
      FacesNearPolyline(m, {Vec3(0.2, 0.5, 0), Vec3(0.8, 0.5, 0)}, 0.015);
  ExpectWrongCorridorIsOvercome(m, p, q, corridor);
}

TEST(ConfinedGeodesicTest, PathRunsFromPToQWithTheDistanceAsLength) {
  const Mesh m = Bump();
  const SurfacePoint p = PointAbove(m, 0.3, 0.35), q = PointAbove(m, 0.7, 0.6);
  ConfinedGeodesicSolver solver(m);
  const absl::StatusOr<double> d = solver.Distance(p, q);
  ASSERT_TRUE(d.ok()) << d.status();
  const absl::StatusOr<std::vector<SurfacePoint>> path = solver.Path(p, q);
  ASSERT_TRUE(path.ok()) << path.status();
  ASSERT_GE(path->size(), 2u);
  EXPECT_LT((PositionOf(m, path->front()) - PositionOf(m, p)).norm(), 1e-12);
  EXPECT_LT((PositionOf(m, path->back()) - PositionOf(m, q)).norm(), 1e-12);
  double length = 0;
  for (size_t i = 1; i < path->size(); ++i) {
    length += (PositionOf(m, (*path)[i]) - PositionOf(m, (*path)[i - 1])).norm();
  }
  EXPECT_NEAR(length, *d, 1e-9 * *d);
}

TEST(ConfinedGeodesicTest, NearPairsOfAFineMeshStayInASmallRegion) {
  const Mesh m = gen::Sphere(5, 1.0);  // 20480 faces
  ConfinedGeodesicSolver solver(m);
  ExactGeodesicSolver reference(m);
  const std::vector<SurfacePoint> points = SomePoints(m, 6, 5);
  for (const SurfacePoint& p : points) {
    // A point a few faces away: a corner of a face three edge steps off.
    int32_t f = p.face;
    for (int step = 0; step < 3; ++step) f = Mesh::FaceOf(m.Twin(3 * f + step % 3));
    const SurfacePoint q = *mesh::VertexPoint(m, m.face(f)[0]);
    ASSERT_TRUE(reference.Propagate({p}).ok());
    const absl::StatusOr<double> d = solver.Distance(p, q);
    ASSERT_TRUE(d.ok()) << d.status();
    EXPECT_NEAR(*d, reference.DistanceAt(q), 1e-9 * *d);
    EXPECT_LT(solver.stats().region_faces, m.num_faces() / 20);
  }
}

TEST(ConfinedGeodesicTest, DifferentComponentsAreInfinitelyFar) {
  const Mesh m = gen::TwoComponents(4);
  ConfinedGeodesicSolver solver(m);
  const SurfacePoint p{0, {1.0 / 3, 1.0 / 3, 1.0 / 3}};
  const SurfacePoint q{m.num_faces() - 1, {1.0 / 3, 1.0 / 3, 1.0 / 3}};
  const absl::StatusOr<double> d = solver.Distance(p, q);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(*d, kInfinity);
  EXPECT_EQ(solver.Path(p, q).status().code(), absl::StatusCode::kNotFound);
}

TEST(ConfinedGeodesicTest, InvalidInputsAreRejected) {
  const Mesh m = gen::Sphere(1, 1.0);
  ConfinedGeodesicSolver solver(m);
  const SurfacePoint good{0, {1.0 / 3, 1.0 / 3, 1.0 / 3}};
  EXPECT_EQ(solver.Distance(good, {0, {0.5, 0.2, 0.1}}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(solver.Distance({0, {std::nan(""), 0.5, 0.5}}, good).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(solver.Distance(good, {m.num_faces(), {1, 0, 0}}).status().code(),
            absl::StatusCode::kOutOfRange);
  const int32_t bad_seed[] = {-1};
  EXPECT_EQ(solver.Distance(good, good, bad_seed).status().code(), absl::StatusCode::kOutOfRange);
  // The solver still works after errors.
  const absl::StatusOr<double> d = solver.Distance(good, good);
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(*d, 0);
}

}  // namespace
}  // namespace geodex::geodesic
