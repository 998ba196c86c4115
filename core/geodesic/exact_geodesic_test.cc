#include "core/geodesic/exact_geodesic.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <thread>

#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::geodesic {
namespace {

using mesh::Mesh;
using mesh::SurfacePoint;
using mesh::Vec3;
namespace gen = mesh::gen;
using ::testing::HasSubstr;

SurfacePoint AtVertex(const Mesh& m, int32_t v) { return *mesh::VertexPoint(m, v); }

SurfacePoint InFace(int32_t f, double a, double b) { return {f, {a, b, 1.0 - a - b}}; }

// The point at `t` along the edge from corner i to corner i+1 of face f.
SurfacePoint OnEdge(int32_t f, int i, double t) {
  SurfacePoint p{f, {0, 0, 0}};
  p.w[i] = 1 - t;
  p.w[(i + 1) % 3] = t;
  return p;
}

int32_t NearestVertex(const Mesh& m, const Vec3& x) {
  int32_t best = 0;
  for (int32_t v = 1; v < m.num_vertices(); ++v) {
    if ((m.position(v) - x).norm() < (m.position(best) - x).norm()) best = v;
  }
  return best;
}

double PathLength(const Mesh& m, const std::vector<SurfacePoint>& path) {
  double length = 0;
  for (size_t i = 1; i < path.size(); ++i) {
    length += (PositionOf(m, path[i]) - PositionOf(m, path[i - 1])).norm();
  }
  return length;
}

bool FaceContains(const Mesh& m, int32_t f, const Vec3& x) {
  const auto& t = m.face(f);
  const Vec3 u = m.position(t[1]) - m.position(t[0]), w = m.position(t[2]) - m.position(t[0]);
  const Vec3 n = u.cross(w);
  const Vec3 r = x - m.position(t[0]);
  const double area2 = n.squaredNorm();
  const double bu = r.cross(w).dot(n) / area2, bw = u.cross(r).dot(n) / area2;
  const double off_plane = std::abs(r.dot(n)) / std::sqrt(area2);
  return off_plane < 1e-9 && bu > -1e-9 && bw > -1e-9 && bu + bw < 1 + 1e-9;
}

// Every segment of the path must lie in one face of the mesh.
void ExpectPathOnSurface(const Mesh& m, const std::vector<SurfacePoint>& path) {
  for (size_t i = 1; i < path.size(); ++i) {
    const Vec3 a = PositionOf(m, path[i - 1]), b = PositionOf(m, path[i]);
    bool inside = false;
    for (int32_t f = 0; f < m.num_faces() && !inside; ++f) {
      inside = FaceContains(m, f, a) && FaceContains(m, f, b);
    }
    EXPECT_TRUE(inside) << "segment " << i << " from " << a.transpose() << " to " << b.transpose()
                        << " leaves the surface";
  }
}

TEST(ExactGeodesicTest, JitteredGridVertexSourceIsEuclidean) {
  const Mesh m = gen::Grid(24, 20, 1.2, 1.0, 0.3, 7);
  ExactGeodesicSolver solver(m);
  const int32_t s = NearestVertex(m, Vec3(0.31, 0.42, 0));
  ASSERT_TRUE(solver.Propagate({AtVertex(m, s)}).ok());
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    const double expected = (m.position(v) - m.position(s)).norm();
    EXPECT_NEAR(solver.VertexDistance(v), expected, 1e-12 * (1 + expected)) << "vertex " << v;
    EXPECT_EQ(solver.NearestSource(v), 0);
  }
}

TEST(ExactGeodesicTest, JitteredGridFaceAndEdgeSourcesAreEuclidean) {
  const Mesh m = gen::Grid(16, 16, 1.0, 1.0, 0.25, 3);
  ExactGeodesicSolver solver(m);
  const std::vector<SurfacePoint> sources = {InFace(200, 0.2, 0.3), OnEdge(77, 1, 0.37),
                                             OnEdge(300, 2, 0.5)};
  for (const SurfacePoint& src : sources) {
    ASSERT_TRUE(solver.Propagate({src}).ok());
    const Vec3 x = PositionOf(m, src);
    for (int32_t v = 0; v < m.num_vertices(); ++v) {
      const double expected = (m.position(v) - x).norm();
      EXPECT_NEAR(solver.VertexDistance(v), expected, 1e-12) << "vertex " << v;
    }
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 200; ++k) {
      double a = u(rng), b = u(rng);
      if (a + b > 1) a = 1 - a, b = 1 - b;
      const SurfacePoint p = InFace(static_cast<int32_t>(u(rng) * m.num_faces()), a, b);
      EXPECT_NEAR(solver.DistanceAt(p), (PositionOf(m, p) - x).norm(), 1e-12);
    }
  }
}

TEST(ExactGeodesicTest, PathLengthEqualsDistanceAndIsStraightOnAPlane) {
  const Mesh m = gen::Grid(20, 20, 1.0, 1.0, 0.3, 11);
  ExactGeodesicSolver solver(m);
  const SurfacePoint src = InFace(15, 0.3, 0.3);
  ASSERT_TRUE(solver.Propagate({src}).ok());
  const SurfacePoint target = InFace(700, 0.1, 0.6);
  auto path = solver.PathTo(target);
  ASSERT_TRUE(path.ok()) << path.status();
  ASSERT_GE(path->size(), 3u);
  const Vec3 a = PositionOf(m, src), b = PositionOf(m, target);
  EXPECT_NEAR((PositionOf(m, path->front()) - b).norm(), 0, 1e-15);
  EXPECT_NEAR((PositionOf(m, path->back()) - a).norm(), 0, 1e-15);
  EXPECT_NEAR(PathLength(m, *path), (a - b).norm(), 1e-12);
  for (const SurfacePoint& p : *path) {  // every point lies on the segment
    const Vec3 x = PositionOf(m, p);
    EXPECT_NEAR((x - a).cross(b - a).norm() / (b - a).norm(), 0, 1e-12);
  }
  ExpectPathOnSurface(m, *path);
}

TEST(ExactGeodesicTest, LShapePathBendsAroundTheReentrantCorner) {
  const double size = 2.0;
  const Mesh m = gen::LShape(10, size);
  ExactGeodesicSolver solver(m);
  // From the top of the left arm to the right end of the bottom arm: the
  // straight segment leaves the domain, the geodesic bends at (1, 1).
  const Vec3 corner(1, 1, 0);
  const int32_t s = NearestVertex(m, Vec3(0.1, 1.9, 0));
  const int32_t t = NearestVertex(m, Vec3(1.9, 0.1, 0));
  ASSERT_TRUE(solver.Propagate({AtVertex(m, s)}).ok());
  const double expected = (m.position(s) - corner).norm() + (corner - m.position(t)).norm();
  EXPECT_NEAR(solver.VertexDistance(t), expected, 1e-12);
  auto path = solver.PathTo(AtVertex(m, t));
  ASSERT_TRUE(path.ok()) << path.status();
  EXPECT_NEAR(PathLength(m, *path), expected, 1e-12);
  bool through_corner = false;
  for (const SurfacePoint& p : *path) through_corner |= (PositionOf(m, p) - corner).norm() < 1e-12;
  EXPECT_TRUE(through_corner);
  ExpectPathOnSurface(m, *path);
  // Points that see the source directly stay Euclidean.
  const int32_t u = NearestVertex(m, Vec3(0.9, 0.2, 0));
  EXPECT_NEAR(solver.VertexDistance(u), (m.position(u) - m.position(s)).norm(), 1e-12);
}

TEST(ExactGeodesicTest, SquareWithHoleGoesAroundTheHole) {
  const Mesh m = gen::SquareWithHole(12, 3.0);  // hole [1,2]^2
  ExactGeodesicSolver solver(m);
  const int32_t s = NearestVertex(m, Vec3(1.5, 0.5, 0));
  const int32_t t = NearestVertex(m, Vec3(1.5, 2.5, 0));
  ASSERT_TRUE(solver.Propagate({AtVertex(m, s)}).ok());
  // Around either side: (1.5,0.5) -> (1,1) -> (1,2) -> (1.5,2.5).
  const double expected = 2 * std::sqrt(0.5) + 1.0;
  EXPECT_NEAR(solver.VertexDistance(t), expected, 1e-12);
  auto path = solver.PathTo(AtVertex(m, t));
  ASSERT_TRUE(path.ok());
  EXPECT_NEAR(PathLength(m, *path), expected, 1e-12);
  ExpectPathOnSurface(m, *path);
}

TEST(ExactGeodesicTest, FoldedSheetEqualsUnfoldedDistance) {
  const int nx = 16, ny = 10;
  const double width = 2.0, height = 1.0;
  const Mesh flat = gen::Grid(nx, ny, width, height);
  const Mesh folded = gen::FoldedSheet(nx, ny, width, height, 1.2);
  ASSERT_EQ(flat.num_vertices(), folded.num_vertices());
  ExactGeodesicSolver solver(folded);
  for (const SurfacePoint& src : {AtVertex(folded, 3), InFace(41, 0.2, 0.5)}) {
    ASSERT_TRUE(solver.Propagate({src}).ok());
    const Vec3 x = PositionOf(flat, src);
    for (int32_t v = 0; v < folded.num_vertices(); ++v) {
      EXPECT_NEAR(solver.VertexDistance(v), (flat.position(v) - x).norm(), 1e-12);
    }
  }
}

TEST(ExactGeodesicTest, CylinderEqualsUnrolledDistance) {
  const int n_around = 24, n_along = 8;
  const double radius = 1.0, length = 3.0;
  const Mesh m = gen::Cylinder(n_around, n_along, radius, length);
  ExactGeodesicSolver solver(m);
  ASSERT_TRUE(solver.Propagate({AtVertex(m, 0)}).ok());
  const double chord = 2 * radius * std::sin(std::numbers::pi / n_around);
  for (int j = 0; j <= n_along; ++j) {
    for (int k = 0; k < n_around; ++k) {
      const int steps = std::min(k, n_around - k);
      const double expected = std::hypot(steps * chord, length * j / n_along);
      EXPECT_NEAR(solver.VertexDistance(j * n_around + k), expected, 1e-12)
          << "k=" << k << " j=" << j;
    }
  }
}

TEST(ExactGeodesicTest, CubeCornerToOppositeCornerIsSqrt5) {
  const double size = 2.0;
  const Mesh m = gen::Cube(6, size);
  ExactGeodesicSolver solver(m);
  const int32_t a = NearestVertex(m, Vec3(0, 0, 0));
  const int32_t b = NearestVertex(m, Vec3(size, size, size));
  const int32_t c = NearestVertex(m, Vec3(size, size, 0));
  const int32_t top_center = NearestVertex(m, Vec3(1, 1, size));
  ASSERT_TRUE(solver.Propagate({AtVertex(m, a)}).ok());
  EXPECT_NEAR(solver.VertexDistance(b), std::sqrt(5.0) * size, 1e-12);
  EXPECT_NEAR(solver.VertexDistance(c), std::sqrt(2.0) * size, 1e-12);
  // Bottom-face corner to top-face centre: unfold across a side face.
  EXPECT_NEAR(solver.VertexDistance(top_center), std::hypot(1.0, 2.0 + 1.0), 1e-12);
  auto path = solver.PathTo(AtVertex(m, b));
  ASSERT_TRUE(path.ok());
  EXPECT_NEAR(PathLength(m, *path), std::sqrt(5.0) * size, 1e-12);
  ExpectPathOnSurface(m, *path);
}

TEST(ExactGeodesicTest, SphereApproachesGreatCircleDistance) {
  double previous_error = 1;
  for (int subdivisions : {3, 4, 5}) {
    const Mesh m = gen::Sphere(subdivisions, 1.0);
    ExactGeodesicSolver solver(m);
    ASSERT_TRUE(solver.Propagate({AtVertex(m, 0)}).ok());
    double max_error = 0;
    const Vec3 p = m.position(0).normalized();
    for (int32_t v = 0; v < m.num_vertices(); ++v) {
      const double exact = std::acos(std::clamp(p.dot(m.position(v).normalized()), -1.0, 1.0));
      if (exact < 0.3) continue;  // relative error is noisy next to the source
      max_error = std::max(max_error, std::abs(solver.VertexDistance(v) - exact) / exact);
      // An inscribed polyhedron is shorter than the sphere.
      EXPECT_LE(solver.VertexDistance(v), exact * (1 + 1e-9));
    }
    EXPECT_LT(max_error, previous_error);
    previous_error = max_error;
  }
  EXPECT_LT(previous_error, 0.01);
}

TEST(ExactGeodesicTest, DisjointComponentsAreInfinitelyFar) {
  const Mesh m = gen::TwoComponents(6);
  ASSERT_EQ(m.num_components(), 2);
  ExactGeodesicSolver solver(m);
  ASSERT_TRUE(solver.Propagate({AtVertex(m, 0)}).ok());
  int reached = 0;
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    if (m.VertexComponent(v) == m.VertexComponent(0)) {
      EXPECT_LT(solver.VertexDistance(v), kInfinity);
      ++reached;
    } else {
      EXPECT_EQ(solver.VertexDistance(v), kInfinity);
      EXPECT_EQ(solver.NearestSource(v), mesh::kNone);
    }
  }
  EXPECT_GT(reached, 0);
  int32_t far_face = 0;
  while (m.FaceComponent(far_face) == m.VertexComponent(0)) ++far_face;
  const SurfacePoint far = InFace(far_face, 0.3, 0.3);
  EXPECT_EQ(solver.DistanceAt(far), kInfinity);
  EXPECT_EQ(solver.PathTo(far).status().code(), absl::StatusCode::kNotFound);
}

TEST(ExactGeodesicTest, MultiSourceGivesVoronoiAndMinimum) {
  const Mesh m = gen::Grid(20, 20, 1.0, 1.0, 0.2, 9);
  ExactGeodesicSolver solver(m);
  const std::vector<SurfacePoint> sources = {InFace(10, 0.3, 0.3), AtVertex(m, 300),
                                             OnEdge(650, 0, 0.4)};
  ASSERT_TRUE(solver.Propagate(sources).ok());
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    double best = kInfinity;
    int32_t nearest = -1;
    for (int32_t s = 0; s < 3; ++s) {
      const double d = (m.position(v) - PositionOf(m, sources[s])).norm();
      if (d < best) best = d, nearest = s;
    }
    EXPECT_NEAR(solver.VertexDistance(v), best, 1e-12);
    // Ties are ambiguous; only check clear cases.
    double second = kInfinity;
    for (int32_t s = 0; s < 3; ++s) {
      const double d = (m.position(v) - PositionOf(m, sources[s])).norm();
      if (s != nearest) second = std::min(second, d);
    }
    if (second - best > 1e-9) {
      EXPECT_EQ(solver.NearestSource(v), nearest) << v;
    }
  }
}

TEST(ExactGeodesicTest, StopRadiusLeavesFarVerticesUnreached) {
  const Mesh m = gen::Grid(30, 30, 1.0, 1.0, 0.2, 2);
  ExactGeodesicSolver solver(m);
  const int32_t s = NearestVertex(m, Vec3(0.5, 0.5, 0));
  GeodesicOptions options;
  options.stop_radius = 0.2;
  ASSERT_TRUE(solver.Propagate({AtVertex(m, s)}, options).ok());
  const int64_t limited = solver.stats().windows_created;
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    const double e = (m.position(v) - m.position(s)).norm();
    if (e <= 0.2) {
      EXPECT_NEAR(solver.VertexDistance(v), e, 1e-12);
    }
    if (e > 0.2 + 0.1) {
      EXPECT_EQ(solver.VertexDistance(v), kInfinity);
    }
  }
  ASSERT_TRUE(solver.Propagate({AtVertex(m, s)}).ok());
  EXPECT_LT(limited * 4, solver.stats().windows_created);
}

// A bounded propagation lists what it reached, so that a caller reads the
// vertices within the radius without scanning the mesh; a reused solver
// lists the second run's vertices only.
TEST(ExactGeodesicTest, ReachedVerticesAreTheFiniteOnes) {
  const Mesh m = gen::Torus(40, 16, 1.0, 0.35);
  ExactGeodesicSolver solver(m);
  GeodesicOptions options;
  options.stop_radius = 0.5;
  for (const SurfacePoint& source : {AtVertex(m, 7), InFace(300, 0.2, 0.3)}) {
    ASSERT_TRUE(solver.Propagate({source}, options).ok());
    std::vector<int32_t> reached(solver.ReachedVertices().begin(), solver.ReachedVertices().end());
    std::sort(reached.begin(), reached.end());
    EXPECT_EQ(std::adjacent_find(reached.begin(), reached.end()), reached.end());
    std::vector<int32_t> finite;
    for (int32_t v = 0; v < m.num_vertices(); ++v) {
      if (solver.VertexDistance(v) < kInfinity) finite.push_back(v);
    }
    EXPECT_EQ(reached, finite);
    EXPECT_GT(finite.size(), 10u);
    EXPECT_LT(finite.size(), static_cast<size_t>(m.num_vertices() / 2));
  }
}

TEST(ExactGeodesicTest, MaxVerticesStopsAPropagationOverItsBudget) {
  const Mesh m = gen::Torus(40, 16, 1.0, 0.35);
  ExactGeodesicSolver solver(m);
  GeodesicOptions options;
  options.max_vertices = 50;
  const absl::Status status = solver.Propagate({AtVertex(m, 7)}, options);
  EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(status.message()), HasSubstr("more than 50 vertices"));
  EXPECT_LE(solver.ReachedVertices().size(), 60u);  // stopped at once, not at the end
  // Within the budget it answers as without one.
  options.max_vertices = m.num_vertices();
  ASSERT_TRUE(solver.Propagate({AtVertex(m, 7)}, options).ok());
  const std::vector<double> bounded = solver.VertexDistances();
  ASSERT_TRUE(solver.Propagate({AtVertex(m, 7)}).ok());
  EXPECT_EQ(bounded, solver.VertexDistances());
}

TEST(ExactGeodesicTest, StopTargetsSettlesThemEarly) {
  const Mesh m = gen::Grid(40, 40, 1.0, 1.0, 0.2, 4);
  ExactGeodesicSolver solver(m);
  const SurfacePoint src = AtVertex(m, NearestVertex(m, Vec3(0.1, 0.1, 0)));
  const int32_t target_vertex = NearestVertex(m, Vec3(0.2, 0.15, 0));
  const SurfacePoint target_point = InFace(123, 0.2, 0.7);
  GeodesicOptions options;
  options.stop_vertices = {target_vertex};
  options.stop_points = {target_point};
  ASSERT_TRUE(solver.Propagate({src}, options).ok());
  const int64_t early = solver.stats().windows_created;
  const Vec3 x = PositionOf(m, src);
  EXPECT_NEAR(solver.VertexDistance(target_vertex), (m.position(target_vertex) - x).norm(), 1e-12);
  EXPECT_NEAR(solver.DistanceAt(target_point), (PositionOf(m, target_point) - x).norm(), 1e-12);
  ASSERT_TRUE(solver.Propagate({src}).ok());
  EXPECT_LT(early * 4, solver.stats().windows_created);
}

// Pruned by a bound on the distance to a point, a propagation keeps that
// point's distance exact, bending round a hole and on a curved surface, with
// fewer windows; a bound below the distance loses it.
TEST(ExactGeodesicTest, PruningKeepsThePointExact) {
  for (const Mesh& m : {gen::SquareWithHole(30, 1.0), gen::Torus(40, 20, 1.0, 0.4)}) {
    ExactGeodesicSolver solver(m);
    std::mt19937 rng(3);
    for (int k = 0; k < 20; ++k) {
      const SurfacePoint p = InFace(static_cast<int32_t>(rng() % m.num_faces()), 0.2, 0.3);
      const SurfacePoint q = InFace(static_cast<int32_t>(rng() % m.num_faces()), 0.5, 0.1);
      ASSERT_TRUE(solver.Propagate({p}).ok());
      const double d = solver.DistanceAt(q);
      const int64_t all = solver.stats().windows_created;
      GeodesicOptions options;
      options.prune_length = d;
      options.prune_point = PositionOf(m, q);
      ASSERT_TRUE(solver.Propagate({p}, options).ok());
      EXPECT_NEAR(solver.DistanceAt(q), d, 1e-12 * d) << m.num_faces() << " pair " << k;
      EXPECT_LT(solver.stats().windows_created, all);
      options.prune_length = 0.5 * d;
      ASSERT_TRUE(solver.Propagate({p}, options).ok());
      EXPECT_GT(solver.DistanceAt(q), d);
    }
  }
}

TEST(ExactGeodesicTest, InitialDistancesCombineWithNewSource) {
  const Mesh m = gen::Grid(20, 20, 1.0, 1.0, 0.2, 8);
  ExactGeodesicSolver solver(m);
  const SurfacePoint a = AtVertex(m, 0), b = AtVertex(m, m.num_vertices() - 1);
  ASSERT_TRUE(solver.Propagate({a}).ok());
  const std::vector<double> first = solver.VertexDistances();
  GeodesicOptions options;
  options.initial_distance = first;
  ASSERT_TRUE(solver.Propagate({b}, options).ok());
  const int64_t incremental = solver.stats().windows_created;
  ASSERT_TRUE(solver.Propagate({b}).ok());
  const std::vector<double> second = solver.VertexDistances();
  EXPECT_LT(incremental, solver.stats().windows_created);
  ASSERT_TRUE(solver.Propagate({a, b}).ok());
  ASSERT_TRUE(solver.Propagate({b}, options).ok());
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    EXPECT_NEAR(solver.VertexDistance(v), std::min(first[v], second[v]), 1e-12);
  }
}

TEST(ExactGeodesicTest, NearlyDegenerateTrianglesStayFiniteAndExact) {
  // A strip 8 long and 1e-6 wide of alternating slivers: every face has an
  // angle within 1e-6 of pi.
  std::vector<Vec3> positions;
  std::vector<mesh::Triangle> faces;
  const int n = 8;
  for (int i = 0; i <= n; ++i) positions.push_back(Vec3(i, 0, 0));
  for (int i = 0; i <= n; ++i) positions.push_back(Vec3(i + 0.5 * (i % 2), 1e-6, 0));
  for (int i = 0; i < n; ++i) {
    faces.push_back({i, i + 1, n + 1 + i});
    faces.push_back({i + 1, n + 2 + i, n + 1 + i});
  }
  auto m = Mesh::Create(positions, faces, "slivers");
  ASSERT_TRUE(m.ok()) << m.status();
  ExactGeodesicSolver solver(*m);
  for (int32_t s = 0; s < m->num_vertices(); ++s) {
    ASSERT_TRUE(solver.Propagate({AtVertex(*m, s)}).ok());
    for (int32_t v = 0; v < m->num_vertices(); ++v) {
      ASSERT_TRUE(std::isfinite(solver.VertexDistance(v)));
      EXPECT_NEAR(solver.VertexDistance(v), (m->position(v) - m->position(s)).norm(), 1e-12);
    }
  }
}

TEST(ExactGeodesicTest, TorusAndDoubleTorusSatisfyTriangleInequality) {
  for (const Mesh& m : {gen::Torus(32, 16, 2.0, 0.7), gen::DoubleTorus(8, 4.0)}) {
    ExactGeodesicSolver solver(m);
    ASSERT_TRUE(solver.Propagate({AtVertex(m, 0)}).ok());
    for (int32_t h = 0; h < m.num_halfedges(); ++h) {
      const double a = solver.VertexDistance(m.Origin(h)), b = solver.VertexDistance(m.Dest(h));
      ASSERT_TRUE(std::isfinite(a));
      EXPECT_LE(std::abs(a - b), m.Length(h) * (1 + 1e-12));
    }
    for (int32_t v : {7, m.num_vertices() / 2, m.num_vertices() - 1}) {
      auto path = solver.PathTo(AtVertex(m, v));
      ASSERT_TRUE(path.ok()) << path.status();
      EXPECT_NEAR(PathLength(m, *path), solver.VertexDistance(v), 1e-9);
      ExpectPathOnSurface(m, *path);
    }
  }
}

TEST(ExactGeodesicTest, ParallelSolversShareOneMesh) {
  const Mesh m = gen::Sphere(3, 1.0);
  std::vector<std::vector<double>> results(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      ExactGeodesicSolver solver(m);
      EXPECT_TRUE(solver.Propagate({AtVertex(m, t * 10)}).ok());
      results[t] = solver.VertexDistances();
    });
  }
  for (auto& t : threads) t.join();
  for (int t = 0; t < 4; ++t) {
    ExactGeodesicSolver solver(m);
    ASSERT_TRUE(solver.Propagate({AtVertex(m, t * 10)}).ok());
    EXPECT_EQ(results[t], solver.VertexDistances());
  }
}

// A C-shaped piece of a torus with a notch cut into its top.
std::vector<uint8_t> TorusRegion(const Mesh& m) {
  std::vector<uint8_t> region(m.num_faces(), 0);
  for (int32_t f = 0; f < m.num_faces(); ++f) {
    Vec3 c = Vec3::Zero();
    for (const int32_t v : m.face(f)) c += m.position(v) / 3;
    const double theta = std::atan2(c.y(), c.x()) + std::numbers::pi;  // [0, 2pi]
    const bool notch = theta > 2.0 && theta < 2.5 && c.z() > 0.1;
    region[f] = theta < 1.5 * std::numbers::pi && !notch;
  }
  return region;
}

TEST(ExactGeodesicTest, FaceRegionPropagatesAsItsSubMesh) {
  const Mesh m = gen::Torus(40, 16, 1.0, 0.35);
  const std::vector<uint8_t> region = TorusRegion(m);
  // The region as a mesh of its own.
  std::vector<int32_t> local(m.num_vertices(), -1), global;
  std::vector<Vec3> positions;
  std::vector<mesh::Triangle> faces;
  int32_t source_face = -1;
  for (int32_t f = 0; f < m.num_faces(); ++f) {
    if (!region[f]) continue;
    mesh::Triangle t;
    for (int k = 0; k < 3; ++k) {
      const int32_t v = m.face(f)[k];
      if (local[v] < 0) {
        local[v] = static_cast<int32_t>(positions.size());
        positions.push_back(m.position(v));
        global.push_back(v);
      }
      t[k] = local[v];
    }
    if (source_face < 0 && faces.size() == 200) source_face = f;
    faces.push_back(t);
  }
  const absl::StatusOr<Mesh> sub = Mesh::Create(positions, faces, "torus region");
  ASSERT_TRUE(sub.ok()) << sub.status();
  ASSERT_GT(sub->num_boundary_edges(), 0);

  const SurfacePoint source{source_face, {0.2, 0.3, 0.5}};
  const SurfacePoint sub_source{200, source.w};
  ExactGeodesicSolver whole(m), part(*sub);
  GeodesicOptions options;
  options.face_region = region;
  ASSERT_TRUE(whole.Propagate({source}, options).ok());
  ASSERT_TRUE(part.Propagate({sub_source}).ok());
  for (int32_t v = 0; v < sub->num_vertices(); ++v) {
    const double want = part.VertexDistance(v);
    ASSERT_LT(want, kInfinity);
    EXPECT_NEAR(whole.VertexDistance(global[v]), want, 1e-10 * want) << "vertex " << global[v];
  }
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    if (local[v] < 0) {
      EXPECT_EQ(whole.VertexDistance(v), kInfinity);
    }
  }
  // The whole region was reached: windows stopped at both ends of the C and
  // at the notch, each on an edge leaving the region.
  ASSERT_FALSE(whole.BorderWindows().empty());
  for (const ExactGeodesicSolver::BorderWindow& w : whole.BorderWindows()) {
    EXPECT_FALSE(region[Mesh::FaceOf(w.h)]);
    EXPECT_TRUE(region[Mesh::FaceOf(m.Twin(w.h))]);
  }
  EXPECT_EQ(whole.SettledBelow(), kInfinity);
}

TEST(ExactGeodesicTest, PropagationsLeaveNoStateBehind) {
  const Mesh m = gen::Torus(40, 16, 1.0, 0.35);
  const std::vector<uint8_t> region = TorusRegion(m);
  int32_t in_region = 0;
  while (!region[in_region]) ++in_region;
  const SurfacePoint a = AtVertex(m, 7), b = InFace(in_region, 0.3, 0.3);
  const SurfacePoint c = OnEdge(m.num_faces() - 1, 1, 0.4);
  GeodesicOptions confined;
  confined.face_region = region;
  GeodesicOptions stopped;
  stopped.stop_points = {AtVertex(m, 9)};
  std::vector<double> initial(m.num_vertices(), kInfinity);
  initial[100] = 0.25;
  GeodesicOptions from_initial;
  from_initial.initial_distance = initial;

  ExactGeodesicSolver reused(m);
  const std::vector<std::pair<SurfacePoint, const GeodesicOptions*>> runs = {
      {a, nullptr},   {b, &confined}, {c, &stopped}, {a, &from_initial},
      {b, &confined}, {c, nullptr},   {b, &stopped}, {a, nullptr}};
  for (const auto& [source, options] : runs) {
    const GeodesicOptions& o = options != nullptr ? *options : GeodesicOptions{};
    ExactGeodesicSolver fresh(m);
    ASSERT_TRUE(fresh.Propagate({source}, o).ok());
    ASSERT_TRUE(reused.Propagate({source}, o).ok());
    EXPECT_EQ(reused.VertexDistances(), fresh.VertexDistances());
    EXPECT_EQ(reused.NearestSources(), fresh.NearestSources());
    EXPECT_EQ(reused.DistanceAt(c), fresh.DistanceAt(c));
    EXPECT_EQ(reused.BorderWindows().size(), fresh.BorderWindows().size());
  }
}

TEST(ExactGeodesicTest, InvalidFaceRegionsAreRejected) {
  const Mesh m = gen::Grid(4, 4, 1.0, 1.0);
  ExactGeodesicSolver solver(m);
  std::vector<uint8_t> region(m.num_faces() - 1, 1);
  GeodesicOptions options;
  options.face_region = region;
  EXPECT_EQ(solver.Propagate({AtVertex(m, 0)}, options).code(), absl::StatusCode::kInvalidArgument);
  region.assign(m.num_faces(), 1);
  region[3] = 0;
  options.face_region = region;
  const absl::Status status = solver.Propagate({InFace(3, 0.2, 0.2)}, options);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("outside the face region"));
  EXPECT_TRUE(solver.Propagate({InFace(4, 0.2, 0.2)}, options).ok());
}

TEST(ExactGeodesicTest, InvalidSourcesAreRejected) {
  const Mesh m = gen::Grid(4, 4, 1.0, 1.0);
  ExactGeodesicSolver solver(m);
  EXPECT_EQ(solver.Propagate({}).code(), absl::StatusCode::kInvalidArgument);
  const SurfacePoint bad_face{999, {1, 0, 0}};
  EXPECT_EQ(solver.Propagate({bad_face}).code(), absl::StatusCode::kOutOfRange);
  const SurfacePoint bad_weights{0, {0.5, 0.2, 0.2}};
  const absl::Status status = solver.Propagate({bad_weights});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("sum"));
  const SurfacePoint nan_weights{0, {NAN, 0.5, 0.5}};
  EXPECT_EQ(solver.Propagate({nan_weights}).code(), absl::StatusCode::kInvalidArgument);
  GeodesicOptions options;
  std::vector<double> wrong_size(3, 0.0);
  options.initial_distance = wrong_size;
  EXPECT_EQ(solver.Propagate({AtVertex(m, 0)}, options).code(), absl::StatusCode::kInvalidArgument);
  options = {};
  options.max_windows = 5;
  EXPECT_EQ(solver.Propagate({AtVertex(m, 0)}, options).code(),
            absl::StatusCode::kResourceExhausted);
}

}  // namespace
}  // namespace geodex::geodesic
