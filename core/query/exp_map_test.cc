#include "core/query/exp_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>

#include "absl/container/flat_hash_map.h"
#include "core/mesh/broken_meshes_testing.h"
#include "core/mesh/generators.h"
#include "core/query/input_queries.h"
#include "core/common/status_macros.h"
#include "core/query/engine/query_engine.h"
#include "core/build/build_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

namespace gen = mesh::gen;
using mesh::Mesh;
using mesh::Vec3;
using ::testing::HasSubstr;

constexpr double kPi = std::numbers::pi;

struct Planar {
  double x = 0, y = 0;
};
double Dist(Planar a, Planar b) { return std::hypot(a.x - b.x, a.y - b.y); }

std::shared_ptr<const QueryEngine> MakeEngine(const Mesh& m, int32_t samples) {
  return geodex::testing::TestEngineOrThrow(m, samples);
}

// The map round `centre`, given in the input's ids, over `engine`: the
// generated meshes need no repair, so the input's ids are the engine's.
absl::StatusOr<std::vector<ExpMapVertex>> EngineMap(const QueryEngine& engine,
                                                    const SurfacePoint& centre,
                                                    const ExpMapOptions& options) {
  // The engine outlives the call: a non-owning pointer.
  GEODEX_ASSIGN_OR_RETURN(
      auto queries,
      InputQueries::Create(std::shared_ptr<const QueryEngine>(&engine, [](const QueryEngine*) {})));
  EnginePoints read;
  GEODEX_RETURN_IF_ERROR(queries->Read(std::span(&centre, 1), Named("centre"), &read));
  return ExpMap(*queries, read, 0, options);
}

std::vector<ExpMapVertex> MapOrDie(const QueryEngine& engine, const SurfacePoint& centre,
                                   double radius, std::optional<Vec3> direction = std::nullopt) {
  ExpMapOptions options;
  options.radius = radius;
  options.reference_direction = direction;
  absl::StatusOr<std::vector<ExpMapVertex>> map = EngineMap(engine, centre, options);
  if (!map.ok()) throw std::runtime_error(std::string(map.status().message()));
  return *std::move(map);
}

// The map of a developable surface must be an isometry onto the plane where
// the distances are those of the developed surface: `planar` gives each
// vertex's developed position. Checks the distances to the centre, the
// distances between mapped vertices, and that exactly the vertices within
// the radius are mapped.
void ExpectIsometry(const Mesh& mesh, const QueryEngine& engine, const SurfacePoint& centre,
                    double radius, const std::vector<Planar>& planar) {
  const std::vector<ExpMapVertex> map = MapOrDie(engine, centre, radius);
  const int32_t* f = mesh.face(centre.face).data();
  Planar c;
  for (int i = 0; i < 3; ++i) {
    c.x += centre.w[i] * planar[f[i]].x;
    c.y += centre.w[i] * planar[f[i]].y;
  }
  std::set<int32_t> mapped;
  double worst_r = 0;
  for (const ExpMapVertex& e : map) {
    mapped.insert(e.vertex);
    const double expected = Dist(planar[e.vertex], c);
    if (expected > 0) worst_r = std::max(worst_r, std::abs(e.r - expected) / expected);
    EXPECT_NEAR(e.r, expected, 1e-5 * std::max(expected, 1e-3)) << "vertex " << e.vertex;
    EXPECT_NEAR(e.u, e.r * std::cos(e.theta), 1e-12);
    EXPECT_NEAR(e.v, e.r * std::sin(e.theta), 1e-12);
  }
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    const double d = Dist(planar[v], c);
    if (d < radius * (1 - 1e-6)) {
      EXPECT_TRUE(mapped.contains(v)) << "missing vertex " << v;
    }
    if (d > radius * (1 + 1e-6)) {
      EXPECT_FALSE(mapped.contains(v)) << "vertex past R: " << v;
    }
  }
  double worst = 0;
  for (size_t i = 0; i < map.size(); ++i) {
    for (size_t j = i + 1; j < map.size(); ++j) {
      const double expected = Dist(planar[map[i].vertex], planar[map[j].vertex]);
      const double got = std::hypot(map[i].u - map[j].u, map[i].v - map[j].v);
      worst = std::max(worst, std::abs(got - expected) / expected);
    }
  }
  EXPECT_LT(worst, 1e-5) << "over " << map.size() << " mapped vertices";
  std::printf("isometry over %zu vertices: worst relative error of r %.1e, of |U_i - U_j| %.1e\n",
              map.size(), worst_r, worst);
  EXPECT_GT(map.size(), 20u);
}

TEST(ExpMapTest, FoldedSheetIsAnIsometry) {
  const int n = 24;
  const Mesh mesh = gen::FoldedSheet(n, n, 2, 2, 1.2);
  std::vector<Planar> planar;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) planar.push_back({2.0 * i / n, 2.0 * j / n});
  }
  const auto engine = MakeEngine(mesh, 60);
  // An interior point left of the fold: the disc crosses it.
  const int32_t face = 2 * (12 * n + 10);
  ExpectIsometry(mesh, *engine, {face, {0.2, 0.3, 0.5}}, 0.7, planar);
  // A vertex of the fold line, and a point on a mesh edge.
  const int32_t* f = mesh.face(face).data();
  for (int i = 0; i < 3; ++i) {
    if (std::abs(planar[f[i]].x - 1) < 1e-12) {
      SurfacePoint at_vertex{face, {0, 0, 0}};
      at_vertex.w[i] = 1;
      ExpectIsometry(mesh, *engine, at_vertex, 0.6, planar);
    }
  }
  ExpectIsometry(mesh, *engine, {face, {0.5, 0.5, 0}}, 0.6, planar);
}

TEST(ExpMapTest, CylinderIsAnIsometry) {
  const int around = 48, along = 24;
  const Mesh mesh = gen::Cylinder(around, along, 1, 4);
  // The prism's sides unrolled, cut opposite vertex column 0.
  const double chord = 2 * std::sin(kPi / around);
  std::vector<Planar> planar;
  for (int j = 0; j <= along; ++j) {
    for (int k = 0; k < around; ++k) {
      const int kk = k < around / 2 ? k : k - around;
      planar.push_back({kk * chord, 4.0 * j / along});
    }
  }
  const auto engine = MakeEngine(mesh, 80);
  // A face of column 0 halfway up, whose vertices are columns 0 and 1.
  const int32_t face = 2 * (12 * around);
  ExpectIsometry(mesh, *engine, {face, {0.3, 0.3, 0.4}}, 1.5, planar);
}

TEST(ExpMapTest, ConeIsAnIsometryAwayFromItsApex) {
  const int around = 64, along = 32;
  const double radius = 1, height = 1;
  const Mesh mesh = gen::Cone(around, along, radius, height);
  // The pyramid's sides developed round the apex: a vertex of ring j and
  // column k lies on the side edge from the apex to base vertex k.
  const double slant = std::hypot(radius, height);
  const double apex_angle = 2 * std::asin(radius * std::sin(kPi / around) / slant);
  std::vector<Planar> planar = {{0, 0}};
  for (int j = 1; j <= along; ++j) {
    for (int k = 0; k < around; ++k) {
      const int kk = k < around / 2 ? k : k - around;
      const double s = slant * j / along;
      planar.push_back({s * std::cos(kk * apex_angle), s * std::sin(kk * apex_angle)});
    }
  }
  const auto engine = MakeEngine(mesh, 100);
  // The vertex of ring 24, column 0 (slant 1.06 from the apex): the disc
  // of radius 0.5 keeps clear of the apex.
  const int32_t v = 1 + 23 * around;
  int32_t face = -1, corner = -1;
  for (int32_t g = 0; g < mesh.num_faces() && face < 0; ++g) {
    for (int i = 0; i < 3; ++i) {
      if (mesh.face(g)[i] == v) face = g, corner = i;
    }
  }
  SurfacePoint centre{face, {0, 0, 0}};
  centre.w[corner] = 1;
  ExpectIsometry(mesh, *engine, centre, 0.5, planar);
}

TEST(ExpMapTest, ApexOfAConeGetsAFullTurn) {
  const int around = 32;
  const Mesh mesh = gen::Cone(around, 8, 1, 2);  // the apex angle sums to well under 2 pi
  const auto engine = MakeEngine(mesh, 40);
  const std::vector<ExpMapVertex> map = MapOrDie(*engine, {0, {1, 0, 0}}, 0.3);
  std::vector<double> ring;
  for (const ExpMapVertex& e : map) {
    if (e.vertex == 0) {
      EXPECT_EQ(e.r, 0);
      continue;
    }
    EXPECT_LE(e.vertex, around) << "only the first ring is within 0.3";
    ring.push_back(e.theta);
  }
  ASSERT_EQ(ring.size(), static_cast<size_t>(around));
  std::sort(ring.begin(), ring.end());
  for (size_t i = 0; i + 1 < ring.size(); ++i) {
    EXPECT_NEAR(ring[i + 1] - ring[i], 2 * kPi / around, 1e-9);
  }
}

TEST(ExpMapTest, FlatSheetFromItsBoundary) {
  const int n = 16;
  const Mesh mesh = gen::Grid(n, n, 1, 1);
  std::vector<Planar> planar;
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    planar.push_back({mesh.position(v).x(), mesh.position(v).y()});
  }
  const auto engine = MakeEngine(mesh, 40);
  // Face 0 holds the corner vertex 0 (a quarter turn) and an edge of the
  // boundary.
  ASSERT_TRUE(mesh.IsBoundaryVertex(mesh.face(0)[0]));
  ExpectIsometry(mesh, *engine, {0, {1, 0, 0}}, 0.5, planar);
  ExpectIsometry(mesh, *engine, {0, {0.5, 0.5, 0}}, 0.5, planar);
  ExpectIsometry(mesh, *engine, {0, {0.2, 0.3, 0.5}}, 0.5, planar);
}

// The analytic log map of the unit sphere round c: r = acos(c . x), theta the
// direction of x projected into the tangent plane at c.
TEST(ExpMapTest, SphereMatchesTheAnalyticLogMap) {
  const Mesh mesh = gen::Sphere(4, 1.0);
  const auto engine = MakeEngine(mesh, 400);
  const SurfacePoint centre{100, {0.3, 0.3, 0.4}};
  const Vec3 reference(0.3, -1, 0.2);
  const std::vector<ExpMapVertex> map = MapOrDie(*engine, centre, 1.2, reference);
  const Vec3 c = mesh::PositionOf(mesh, centre).normalized();
  const Vec3 e1 = (reference - reference.dot(c) * c).normalized(), e2 = c.cross(e1);
  // The mesh's edge length: the scale of the discretisation error.
  const double h = (mesh.position(mesh.face(0)[0]) - mesh.position(mesh.face(0)[1])).norm();
  double worst_r = 0, worst_theta = 0;
  std::vector<double> theta_errors;
  for (const ExpMapVertex& e : map) {
    const Vec3 x = mesh.position(e.vertex).normalized();
    const double r = std::acos(std::clamp(c.dot(x), -1.0, 1.0));
    worst_r = std::max(worst_r, std::abs(e.r - r));
    if (r < 2 * h) continue;  // the angle of a point next to the centre is ill-posed
    const Vec3 t = x - c.dot(x) * c;
    const double theta = std::atan2(t.dot(e2), t.dot(e1));
    theta_errors.push_back(std::abs(std::remainder(e.theta - theta, 2 * kPi)));
    worst_theta = std::max(worst_theta, theta_errors.back());
  }
  ASSERT_GT(theta_errors.size(), 500u);
  std::sort(theta_errors.begin(), theta_errors.end());
  // r is the engine's distance: its error is the index's (m samples), a
  // fraction of an edge. theta's is the discretisation's: the inscribed
  // polyhedron's faces tilt from the tangent planes by about h / 2.
  std::printf(
      "sphere, h = %.4f, %zu vertices: r worst error %.2e; theta error median %.2e, worst "
      "%.2e rad\n",
      h, map.size(), worst_r, theta_errors[theta_errors.size() / 2], worst_theta);
  EXPECT_LT(worst_r, 0.15 * h) << "h = " << h;
  EXPECT_LT(theta_errors[theta_errors.size() / 2], 0.1 * h) << "median, radians";
  EXPECT_LT(worst_theta, 0.5 * h) << "radians";
}

TEST(ExpMapTest, ThetaIsContinuousAwayFromTheCutLocus) {
  const Mesh mesh = gen::Sphere(4, 1.0);
  const auto engine = MakeEngine(mesh, 150);
  const std::vector<ExpMapVertex> map = MapOrDie(*engine, {7, {0.2, 0.5, 0.3}}, 2.5);
  absl::flat_hash_map<int32_t, const ExpMapVertex*> by_vertex;
  for (const ExpMapVertex& e : map) by_vertex[e.vertex] = &e;
  int edges = 0;
  for (int32_t f = 0; f < mesh.num_faces(); ++f) {
    for (int i = 0; i < 3; ++i) {
      const auto a = by_vertex.find(mesh.face(f)[i]), b = by_vertex.find(mesh.face(f)[(i + 1) % 3]);
      if (a == by_vertex.end() || b == by_vertex.end()) continue;
      const double r = std::min(a->second->r, b->second->r);
      if (r < 0.3) continue;
      const double edge = (mesh.position(a->first) - mesh.position(b->first)).norm();
      // Neighbours at distance r on the unit sphere are at most about
      // edge / sin(r) apart in angle (plus the map's error at both); a jump
      // across a seam would be about 2 pi.
      EXPECT_LT(std::abs(std::remainder(a->second->theta - b->second->theta, 2 * kPi)),
                2 * edge / std::sin(r) + 0.02)
          << a->first << "-" << b->first << " at r " << r;
      ++edges;
    }
  }
  EXPECT_GT(edges, 1000);
}

// r is the engine's distance (refined near the centre by one local exact
// propagation), and the map holds exactly the vertices whose r is within the
// radius: on a torus (curved both ways), from a centre next to a saddle
// vertex (its inner equator) and on it.
TEST(ExpMapTest, HoldsExactlyTheVerticesWithinTheRadius) {
  const Mesh mesh = gen::Torus(48, 24, 1, 0.4);
  const auto engine = MakeEngine(mesh, 400);
  int32_t saddle = 0;  // the vertex closest to the z axis
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.position(v).head<2>().norm() < mesh.position(saddle).head<2>().norm()) saddle = v;
  }
  const int32_t face = mesh::Mesh::FaceOf(mesh.Outgoing(saddle)[0]);
  const int corner = mesh.face(face)[0] == saddle ? 0 : mesh.face(face)[1] == saddle ? 1 : 2;
  std::array<double, 3> near_saddle = {0.05, 0.05, 0.05};
  near_saddle[corner] = 0.9;
  std::array<double, 3> at_saddle = {0, 0, 0};
  at_saddle[corner] = 1;
  const double radius = 0.9;
  const double exact_radius = kRefineScale * engine->scale_length();
  ASSERT_LT(exact_radius, radius);  // both kinds of r are in the map
  for (const SurfacePoint centre :
       {SurfacePoint{face, near_saddle}, SurfacePoint{face, at_saddle}}) {
    const std::vector<ExpMapVertex> map = MapOrDie(*engine, centre, radius);
    QueryScratch scratch;
    const std::vector<double> exact(
        engine->LocalExactDistances(centre, exact_radius, scratch)->begin(),
        engine->LocalExactDistances(centre, exact_radius, scratch)->end());
    std::set<int32_t> mapped;
    for (const ExpMapVertex& e : map) {
      mapped.insert(e.vertex);
      ASSERT_TRUE(std::isfinite(e.theta) && e.theta > -kPi && e.theta <= kPi);
      EXPECT_LE(e.r, radius);
    }
    int exact_count = 0;
    for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
      SurfacePoint p{mesh::Mesh::FaceOf(mesh.Outgoing(v)[0]), {0, 0, 0}};
      p.w[mesh.face(p.face)[0] == v ? 0 : mesh.face(p.face)[1] == v ? 1 : 2] = 1;
      const double distance = engine->Distance(centre, p).value();
      const bool near = exact[v] <= exact_radius;
      exact_count += near;
      // The local exact distance is never above the refined one (a path's
      // length) by more than rounding.
      if (near) {
        EXPECT_LE(exact[v], distance * (1 + 1e-9) + 1e-12) << "vertex " << v;
      }
      const double d = near ? exact[v] : distance;
      EXPECT_EQ(mapped.contains(v), d <= radius) << "vertex " << v << " at " << d;
      if (!mapped.contains(v)) continue;
      const auto e =
          std::lower_bound(map.begin(), map.end(), v,
                           [](const ExpMapVertex& x, int32_t id) { return x.vertex < id; });
      EXPECT_NEAR(e->r, d, 1e-9 * std::max(d, 1.0)) << "vertex " << v;
    }
    EXPECT_GT(exact_count, 10);
    EXPECT_GT(mapped.size(), static_cast<size_t>(exact_count) + 100);
  }
}

TEST(ExpMapTest, RejectsBadArguments) {
  const Mesh mesh = gen::Grid(4, 4, 1, 1);
  const auto engine = MakeEngine(mesh, 8);
  ExpMapOptions options;
  options.radius = 0;
  EXPECT_THAT(EngineMap(*engine, {0, {1, 0, 0}}, options).status().message(), HasSubstr("radius"));
  options.radius = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(EngineMap(*engine, {0, {1, 0, 0}}, options).ok());
  options.radius = 0.5;
  options.reference_direction = Vec3(0, 0, 1);  // the grid's normal
  EXPECT_THAT(EngineMap(*engine, {0, {1, 0, 0}}, options).status().message(),
              HasSubstr("perpendicular"));
  options.reference_direction = Vec3(std::nan(""), 0, 0);
  EXPECT_THAT(EngineMap(*engine, {0, {1, 0, 0}}, options).status().message(), HasSubstr("finite"));
  // Along the reference direction theta is 0; the grid faces +z, so +v
  // points along +z x +y = -x.
  options.reference_direction = Vec3(0, 1, 0);
  const SurfacePoint centre{5, {0.2, 0.3, 0.5}};
  const absl::StatusOr<std::vector<ExpMapVertex>> map = EngineMap(*engine, centre, options);
  ASSERT_TRUE(map.ok()) << map.status();
  ASSERT_FALSE(map->empty());
  const Vec3 c = mesh::PositionOf(mesh, centre);
  for (const ExpMapVertex& e : *map) {
    const Vec3 d = mesh.position(e.vertex) - c;
    EXPECT_NEAR(e.u, d.y(), 1e-9);
    EXPECT_NEAR(e.v, -d.x(), 1e-9);
  }
}

// θ runs round the normal of the centre's input face: where the repair
// re-oriented that face, mirrored against the internal face's.
TEST(ExpMapTest, AReorientedFaceMirrorsTheta) {
  const Mesh sphere = gen::Sphere(2, 1.0);
  mesh::RawMesh raw = mesh::testing::RawOf(sphere, "sphere");
  for (int32_t f : {0, 5, 17, 200}) std::swap(raw.triangles[f][1], raw.triangles[f][2]);
  const auto reoriented = geodex::testing::RepairedTestEngineOrThrow(raw, 40);
  const auto plain =
      geodex::testing::RepairedTestEngineOrThrow(mesh::testing::RawOf(sphere, "sphere"), 40);
  ExpMapOptions options;
  options.radius = 0.5;
  // Input face 5 is (a, c, b) of the sphere's (a, b, c): weights (x, y, z) on
  // it are (x, z, y) on the sphere's face 5.
  absl::StatusOr<std::vector<ExpMapVertex>> mirrored =
      EngineMap(*reoriented.engine, {5, {0.1, 0.2, 0.7}}, options);
  absl::StatusOr<std::vector<ExpMapVertex>> reference =
      EngineMap(*plain.engine, {5, {0.1, 0.7, 0.2}}, options);
  ASSERT_TRUE(mirrored.ok()) << mirrored.status();
  ASSERT_TRUE(reference.ok()) << reference.status();
  ASSERT_EQ(mirrored->size(), reference->size());
  ASSERT_FALSE(reference->empty());
  int turned = 0;
  for (size_t i = 0; i < reference->size(); ++i) {
    const ExpMapVertex& m = (*mirrored)[i];
    const ExpMapVertex& r = (*reference)[i];
    EXPECT_EQ(m.vertex, r.vertex);
    EXPECT_NEAR(m.r, r.r, 1e-9);
    // The sphere's face 5 runs a -> b first, the input's a -> c: θ = 0 lies
    // along another edge, and turns the other way.
    EXPECT_NEAR(m.u * m.u + m.v * m.v, r.r * r.r, 1e-9);
    turned += std::abs(m.theta - r.theta) > 1e-6;
  }
  EXPECT_GT(turned, 0);
}

// With the long-edge split, the map names input vertices only: a midpoint
// is none, and a vertex appears once.
TEST(ExpMapTest, ASplitIndexNamesInputVerticesOnly) {
  const Mesh coarse = gen::Sphere(1, 1.0);
  ASSERT_EQ(coarse.num_vertices(), 42);
  const auto split = geodex::testing::RepairedTestEngineOrThrow(
      mesh::testing::RawOf(coarse, "sphere"), 120, /*split=*/true);
  ASSERT_GT(split.engine->index().split_vertices(), 0);
  ExpMapOptions options;
  options.radius = 1.0;
  absl::StatusOr<std::vector<ExpMapVertex>> map =
      EngineMap(*split.engine, {3, {0.2, 0.3, 0.5}}, options);
  ASSERT_TRUE(map.ok()) << map.status();
  ASSERT_FALSE(map->empty());
  for (size_t i = 0; i < map->size(); ++i) {
    EXPECT_LT((*map)[i].vertex, 42);
    if (i > 0) {
      EXPECT_LT((*map)[i - 1].vertex, (*map)[i].vertex);
    }
  }
}

}  // namespace
}  // namespace geodex::query
