#include "core/geodesic/vertex_geodesic.h"

#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "core/geodesic/exact_geodesic.h"
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

// A sphere with pseudo-random radial bumps: many saddle vertices, the case
// where pseudo-sources and the pruning rules matter most.
Mesh BumpySphere(int subdivisions, double amplitude) {
  const Mesh sphere = gen::Sphere(subdivisions, 1.0);
  std::vector<Vec3> positions = sphere.positions();
  uint64_t state = 12345;
  for (Vec3& p : positions) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const double u = static_cast<double>(state >> 11) * 0x1.0p-53;
    p *= 1.0 + amplitude * (2 * u - 1);
  }
  return *Mesh::Create(std::move(positions), sphere.faces(), "bumpy_sphere");
}

// A jittered grid lifted into a rough height field: irregular triangles of
// every shape, saddles and peaks, with a boundary; like a patch of a scan.
Mesh RoughTerrain(int n) {
  const Mesh grid = gen::Grid(n, n, 1.0, 1.0, 0.35, 3);
  std::vector<Vec3> positions = grid.positions();
  uint64_t state = 777;
  for (Vec3& p : positions) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const double u = static_cast<double>(state >> 11) * 0x1.0p-53;
    p.z() = 0.15 * std::sin(7 * p.x()) * std::cos(5 * p.y()) + 0.02 * (2 * u - 1);
  }
  return *Mesh::Create(std::move(positions), grid.faces(), "rough_terrain");
}

struct Case {
  std::string name;
  std::function<Mesh()> make;
};
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

const Case kCases[] = {
    {"jittered_grid", [] { return gen::Grid(24, 20, 1.2, 1.0, 0.3, 5); }},
    {"l_shape", [] { return gen::LShape(8, 2.0); }},
    {"square_with_hole", [] { return gen::SquareWithHole(18, 3.0); }},
    {"folded_sheet", [] { return gen::FoldedSheet(20, 14, 1.5, 1.0, 1.2); }},
    {"cone", [] { return gen::Cone(24, 10, 1.0, 1.5); }},
    {"cube", [] { return gen::Cube(8, 1.0); }},
    {"sphere", [] { return gen::Sphere(3, 1.0); }},
    {"bumpy_sphere", [] { return BumpySphere(4, 0.08); }},
    {"rough_sphere", [] { return BumpySphere(5, 0.2); }},
    {"rough_terrain", [] { return RoughTerrain(40); }},
    {"torus", [] { return gen::Torus(40, 16, 2.0, 0.7); }},
    {"double_torus", [] { return gen::DoubleTorus(4, 4.0); }},
    {"split_torus", [] { return gen::SplitFacesInFour(gen::Torus(16, 8, 2.0, 0.7)); }},
    {"two_components", [] { return gen::TwoComponents(6); }},
};

class VertexGeodesicAgreementTest : public ::testing::TestWithParam<Case> {};

// Same distances as the window engine (ExactGeodesicSolver, itself checked
// against CGAL and closed forms), from several sources, to rounding.
TEST_P(VertexGeodesicAgreementTest, EqualsTheWindowEngine) {
  const Mesh m = GetParam().make();
  VertexGeodesicSolver fast(m);
  ExactGeodesicSolver reference(m);
  for (const int32_t source : {0, m.num_vertices() / 3, m.num_vertices() - 1}) {
    SCOPED_TRACE(source);
    ASSERT_TRUE(fast.Propagate({source}).ok());
    ASSERT_TRUE(reference.Propagate({*mesh::VertexPoint(m, source)}).ok());
    for (int32_t v = 0; v < m.num_vertices(); ++v) {
      const double want = reference.VertexDistance(v);
      const double got = fast.VertexDistance(v);
      if (std::isinf(want)) {
        EXPECT_EQ(got, want) << "vertex " << v;
        EXPECT_EQ(fast.NearestSource(v), mesh::kNone);
      } else {
        ASSERT_NEAR(got, want, 1e-9 * std::max(want, 1e-3)) << "vertex " << v;
        EXPECT_EQ(fast.NearestSource(v), 0);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Generated, VertexGeodesicAgreementTest, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return info.param.name;
                         });

// Sources anywhere on the surface and target points anywhere: the same as the
// window engine's VertexDistance and DistanceAt.
TEST_P(VertexGeodesicAgreementTest, SurfacePointSourcesAndTargetsEqualTheWindowEngine) {
  const Mesh m = GetParam().make();
  std::vector<SurfacePoint> targets;
  uint64_t state = 99;
  auto uniform = [&] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  };
  for (int k = 0; k < 60; ++k) {
    const int32_t f = static_cast<int32_t>(uniform() * m.num_faces());
    const double a = uniform(), b = uniform() * (1 - a);
    targets.push_back({f, {a, b, 1 - a - b}});
  }
  targets.push_back({3, {0.5, 0.5, 0}});  // on an edge
  targets.push_back({7, {0, 1, 0}});      // at a vertex
  const int32_t f = m.num_faces() / 2;
  const std::vector<SurfacePoint> sources = {
      {f, {0.2, 0.3, 0.5}},                  // inside a face
      {m.num_faces() / 3, {0.25, 0.75, 0}},  // on an edge
      *mesh::VertexPoint(m, m.num_vertices() / 4),
  };
  VertexGeodesicSolver fast(m);
  ExactGeodesicSolver reference(m);
  VertexGeodesicOptions options;
  options.targets = targets;
  for (const SurfacePoint& source : sources) {
    SCOPED_TRACE(source.face);
    ASSERT_TRUE(fast.Propagate({&source, 1}, options).ok());
    ASSERT_TRUE(reference.Propagate({source}).ok());
    for (int32_t v = 0; v < m.num_vertices(); ++v) {
      const double want = reference.VertexDistance(v);
      if (std::isinf(want)) {
        ASSERT_EQ(fast.VertexDistance(v), want) << "vertex " << v;
      } else {
        ASSERT_NEAR(fast.VertexDistance(v), want, 1e-9 * std::max(want, 1e-3)) << "vertex " << v;
      }
    }
    for (size_t i = 0; i < targets.size(); ++i) {
      const double want = reference.DistanceAt(targets[i]);
      if (std::isinf(want)) {
        ASSERT_EQ(fast.TargetDistance(i), want) << "target " << i;
      } else {
        ASSERT_NEAR(fast.TargetDistance(i), want, 1e-9 * std::max(want, 1e-3)) << "target " << i;
      }
    }
  }
  EXPECT_THAT(fast.Propagate({SurfacePoint{m.num_faces(), {1, 0, 0}}}).message(),
              HasSubstr("out of range"));
}

// Repaired meshes keep zero-area faces, including faces with two corners at
// one position (an edge of length 0): no NaN, and on a flat domain both
// engines' distances stay Euclidean. (Before the ends of such an edge were
// made pseudo-sources, the window engine missed straight paths through the
// pinch by up to 8%.)
TEST(VertexGeodesicTest, ZeroLengthEdgesGiveNoNaN) {
  const Mesh grid = gen::Grid(8, 8, 1.0, 1.0);
  for (const int32_t v : {40, 31}) {
    SCOPED_TRACE(v);
    std::vector<Vec3> positions = grid.positions();
    const int32_t u = grid.Dest(grid.Outgoing(v)[0]);
    positions[v] = positions[u];  // edge (v, u) has length 0
    mesh::MeshOptions options;
    options.allow_zero_area_faces = true;
    const absl::StatusOr<Mesh> m = Mesh::Create(positions, grid.faces(), "pinched", options);
    ASSERT_TRUE(m.ok()) << m.status();
    VertexGeodesicSolver fast(*m);
    ExactGeodesicSolver windows(*m);
    for (const int32_t source : {0, 80, u}) {
      ASSERT_TRUE(fast.Propagate({source}).ok());
      ASSERT_TRUE(windows.Propagate({*mesh::VertexPoint(*m, source)}).ok());
      for (int32_t w = 0; w < m->num_vertices(); ++w) {
        const double euclid = (m->position(w) - m->position(source)).norm();
        EXPECT_NEAR(fast.VertexDistance(w), euclid, 1e-9) << "vertex " << w << " from " << source;
        EXPECT_NEAR(windows.VertexDistance(w), euclid, 1e-9)
            << "vertex " << w << " from " << source;
      }
    }
  }
}

TEST(VertexGeodesicTest, FlatConvexDomainGivesEuclideanDistances) {
  const Mesh grid = gen::Grid(30, 20, 3.0, 2.0, 0.25, 9);
  VertexGeodesicSolver solver(grid);
  const int32_t source = 317;
  ASSERT_TRUE(solver.Propagate({source}).ok());
  for (int32_t v = 0; v < grid.num_vertices(); ++v) {
    EXPECT_NEAR(solver.VertexDistance(v), (grid.position(v) - grid.position(source)).norm(), 1e-12);
  }
}

TEST(VertexGeodesicTest, AroundAReentrantCornerTheDistanceBends) {
  // L-shape [0,2]^2 minus [1,2]^2: the re-entrant corner is (1,1). The
  // segment from (2,0.5) to (0,2) leaves the domain, so the path bends there.
  const Mesh l = gen::LShape(8, 2.0);
  int32_t source = mesh::kNone, corner = mesh::kNone, target = mesh::kNone;
  for (int32_t v = 0; v < l.num_vertices(); ++v) {
    const Vec3& p = l.position(v);
    if ((p - Vec3(2, 0.5, 0)).norm() < 1e-12) source = v;
    if ((p - Vec3(1, 1, 0)).norm() < 1e-12) corner = v;
    if ((p - Vec3(0, 2, 0)).norm() < 1e-12) target = v;
  }
  ASSERT_NE(source, mesh::kNone);
  ASSERT_NE(corner, mesh::kNone);
  ASSERT_NE(target, mesh::kNone);
  VertexGeodesicSolver solver(l);
  ASSERT_TRUE(solver.Propagate({source}).ok());
  EXPECT_NEAR(solver.VertexDistance(corner), std::sqrt(1.25), 1e-12);
  EXPECT_NEAR(solver.VertexDistance(target), std::sqrt(1.25) + std::sqrt(2.0), 1e-12);
}

TEST(VertexGeodesicTest, SeveralSourcesGiveTheNearest) {
  const Mesh m = gen::Torus(30, 12, 2.0, 0.6);
  const std::vector<int32_t> sources = {3, 150, 301};
  VertexGeodesicSolver solver(m);
  std::vector<std::vector<double>> single;
  for (int32_t s : sources) {
    ASSERT_TRUE(solver.Propagate({s}).ok());
    single.push_back(solver.VertexDistances());
  }
  ASSERT_TRUE(solver.Propagate(sources).ok());
  for (int32_t v = 0; v < m.num_vertices(); ++v) {
    int32_t nearest = 0;
    for (int32_t i = 1; i < 3; ++i) {
      if (single[i][v] < single[nearest][v]) nearest = i;
    }
    ASSERT_NEAR(solver.VertexDistance(v), single[nearest][v], 1e-12) << v;
    // Ties (equidistant vertices) may go either way.
    if (std::abs(single[0][v] - single[1][v]) > 1e-9 &&
        std::abs(single[0][v] - single[2][v]) > 1e-9 &&
        std::abs(single[1][v] - single[2][v]) > 1e-9) {
      EXPECT_EQ(solver.NearestSource(v), nearest) << v;
    }
  }
}

// Farthest-point sampling's use: a new source over the distances of earlier
// ones gives the minimum of both, and marks exactly the vertices it improved.
TEST(VertexGeodesicTest, InitialDistancesGiveTheMinimumAndOnlyImproveLocally) {
  for (const Mesh& m : {BumpySphere(5, 0.2), RoughTerrain(40), gen::DoubleTorus(4, 4.0)}) {
    SCOPED_TRACE(m.name());
    VertexGeodesicSolver solver(m);
    std::vector<double> field(m.num_vertices(), kInfinity);
    std::vector<double> reference(m.num_vertices(), kInfinity);
    int64_t settled_incrementally = 0;
    for (const int32_t s : {0, m.num_vertices() / 2, m.num_vertices() / 5, m.num_vertices() - 1}) {
      SCOPED_TRACE(s);
      ASSERT_TRUE(solver.Propagate({s}).ok());
      const std::vector<double> alone = solver.VertexDistances();
      VertexGeodesicOptions options;
      options.initial_distance = field;
      ASSERT_TRUE(solver.Propagate({s}, options).ok());
      settled_incrementally += solver.stats().vertices_settled;
      for (int32_t v = 0; v < m.num_vertices(); ++v) {
        const double want = std::min(reference[v], alone[v]);
        ASSERT_NEAR(solver.VertexDistance(v), want, 1e-9 * std::max(want, 1e-3)) << v;
        if (alone[v] < reference[v] * (1 - 1e-9)) {
          EXPECT_EQ(solver.NearestSource(v), 0) << v;
        } else if (alone[v] > reference[v] * (1 + 1e-9)) {
          EXPECT_EQ(solver.NearestSource(v), mesh::kNone) << v;
        }
      }
      for (int32_t v = 0; v < m.num_vertices(); ++v)
        reference[v] = std::min(reference[v], alone[v]);
      field = solver.VertexDistances();
    }
    // Later sources only explore their own cells and a ring around them.
    EXPECT_LT(settled_incrementally, 3 * m.num_vertices());
  }
  const Mesh grid = gen::Grid(2, 2, 1.0, 1.0);
  VertexGeodesicSolver solver(grid);
  const std::vector<double> short_field(4, 1.0);
  VertexGeodesicOptions options;
  options.initial_distance = short_field;
  EXPECT_THAT(solver.Propagate({0}, options).message(),
              HasSubstr("initial_distance has 4 entries, the mesh 9 vertices"));
  std::vector<double> negative(9, 1.0);
  negative[3] = -2;
  options.initial_distance = negative;
  EXPECT_THAT(solver.Propagate({0}, options).message(),
              HasSubstr("initial_distance[3] = -2 is not a distance"));
}

// The new source improves x across the edge (u,w) while u and w keep their
// (shorter) initial distances: the window must not wait forever for u or w.
TEST(VertexGeodesicTest, InitialDistancesDoNotStopTheFrontAtUnimprovedEdges) {
  const Mesh kite = *Mesh::Create({Vec3(-10, 0, 0), Vec3(10, 0, 0), Vec3(0, -1, 0), Vec3(0, 1, 0)},
                                  {{0, 2, 1}, {1, 3, 0}}, "kite");
  const double far = std::sqrt(101.0);
  const std::vector<double> initial = {0, 0, far, far};
  VertexGeodesicOptions options;
  options.initial_distance = initial;
  VertexGeodesicSolver solver(kite);
  ASSERT_TRUE(solver.Propagate({2}, options).ok());
  EXPECT_EQ(solver.VertexDistance(0), 0);
  EXPECT_EQ(solver.NearestSource(0), mesh::kNone);
  EXPECT_NEAR(solver.VertexDistance(3), 2.0, 1e-12);
  EXPECT_EQ(solver.NearestSource(3), 0);
}

TEST(VertexGeodesicTest, KeepsOnlyTheWavefront) {
  const Mesh m = gen::Sphere(6, 1.0);  // 40962 vertices
  VertexGeodesicSolver solver(m);
  ASSERT_TRUE(solver.Propagate({0}).ok());
  // Every window is freed once propagated: the most alive at once is the
  // front's, a small fraction of all created.
  EXPECT_GT(solver.stats().windows_created, 0);
  EXPECT_LT(solver.stats().peak_windows * 20, solver.stats().windows_created);
  EXPECT_EQ(solver.stats().vertices_settled, m.num_vertices());
  // Antipode of vertex 0 at pi (up to the polyhedral approximation).
  double farthest = 0;
  for (double d : solver.VertexDistances()) farthest = std::max(farthest, d);
  EXPECT_NEAR(farthest, std::numbers::pi, 0.01);
}

TEST(VertexGeodesicTest, ASolverIsReusable) {
  const Mesh m = BumpySphere(3, 0.1);
  VertexGeodesicSolver solver(m);
  ASSERT_TRUE(solver.Propagate({5}).ok());
  const std::vector<double> first = solver.VertexDistances();
  ASSERT_TRUE(solver.Propagate({100}).ok());
  ASSERT_TRUE(solver.Propagate({5}).ok());
  EXPECT_EQ(solver.VertexDistances(), first);
}

TEST(VertexGeodesicTest, RejectsBadSources) {
  const Mesh grid = gen::Grid(2, 2, 1.0, 1.0);
  VertexGeodesicSolver solver(grid);
  EXPECT_THAT(solver.Propagate(std::span<const int32_t>()).message(), HasSubstr("no sources"));
  const absl::Status past = solver.Propagate({9});
  EXPECT_EQ(past.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(past.message(), HasSubstr("source vertex 9 out of range [0, 9)"));
  EXPECT_EQ(solver.Propagate({-1}).code(), absl::StatusCode::kOutOfRange);
  const Mesh loose = *Mesh::Create({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(5, 5, 5)},
                                   {{0, 1, 2}}, "loose");
  VertexGeodesicSolver with_loose(loose);
  EXPECT_THAT(with_loose.Propagate({3}).message(), HasSubstr("source vertex 3 belongs to no face"));
  // A window budget far too small is an error, not a partial answer.
  const Mesh sphere = gen::Sphere(3, 1.0);
  VertexGeodesicSolver tight(sphere);
  VertexGeodesicOptions budget;
  budget.max_windows = 100;
  const absl::Status exhausted = tight.Propagate({0}, budget);
  EXPECT_EQ(exhausted.code(), absl::StatusCode::kResourceExhausted);
  // And the solver recovers from it.
  ASSERT_TRUE(tight.Propagate({0}).ok());
  EXPECT_NEAR(tight.VertexDistance(0), 0, 0);
}

}  // namespace
}  // namespace geodex::geodesic
