#include "core/mesh/generators.h"

#include <cmath>
#include <numbers>
#include <set>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::mesh::gen {
namespace {

constexpr double kPi = std::numbers::pi;

struct Topology {
  int euler = 0;  // V - E + F over referenced vertices
  int boundary_edges = 0;
  int boundary_loops = 0;
  int components = 0;
};

Topology TopologyOf(const Mesh& mesh) {
  int referenced = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) referenced += mesh.IsReferenced(v) ? 1 : 0;
  const int boundary = mesh.num_boundary_edges();
  const int edges = (mesh.num_halfedges() - boundary) / 2 + boundary;
  // Boundary loops: follow boundary half-edges. Each boundary vertex of a
  // manifold mesh has exactly one outgoing boundary half-edge.
  std::set<int> seen;
  int loops = 0;
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    if (mesh.Twin(h) != kNone || seen.count(h)) continue;
    ++loops;
    int g = h;
    do {
      seen.insert(g);
      // The next boundary half-edge starts at Dest(g): the first outgoing
      // half-edge of a boundary vertex lies on the boundary.
      g = mesh.Outgoing(mesh.Dest(g)).front();
    } while (g != h && seen.size() <= static_cast<size_t>(mesh.num_halfedges()));
  }
  return {referenced - edges + mesh.num_faces(), boundary, loops, mesh.num_components()};
}

// Signed volume enclosed by a closed mesh (positive when faces point outward).
double SignedVolume(const Mesh& mesh) {
  double volume = 0;
  for (const Triangle& t : mesh.faces()) {
    volume += mesh.position(t[0]).dot(mesh.position(t[1]).cross(mesh.position(t[2]))) / 6;
  }
  return volume;
}

// Every face normal of a flat mesh points to +z.
void ExpectUpwardNormals(const Mesh& mesh) {
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Triangle& t = mesh.face(f);
    const Vec3 n = (mesh.position(t[1]) - mesh.position(t[0]))
                       .cross(mesh.position(t[2]) - mesh.position(t[0]));
    ASSERT_GT(n.z(), 0) << "face " << f;
  }
}

TEST(GeneratorsTest, Grid) {
  const Mesh mesh = Grid(4, 3, 2.0, 1.5);
  EXPECT_EQ(mesh.num_vertices(), 5 * 4);
  EXPECT_EQ(mesh.num_faces(), 2 * 4 * 3);
  const Topology topology = TopologyOf(mesh);
  EXPECT_EQ(topology.euler, 1);
  EXPECT_EQ(topology.boundary_edges, 2 * (4 + 3));
  EXPECT_EQ(topology.boundary_loops, 1);
  EXPECT_EQ(topology.components, 1);
  EXPECT_NEAR(mesh.TotalArea(), 3.0, 1e-12);
  EXPECT_EQ(mesh.BoundingBoxMax(), Vec3(2.0, 1.5, 0));
  ExpectUpwardNormals(mesh);
  // Diagonals alternate: cell (0,0) is split along 0-6, cell (1,0) along 2-6.
  EXPECT_EQ(mesh.face(0), (Triangle{0, 1, 6}));
  EXPECT_EQ(mesh.face(2), (Triangle{1, 2, 6}));
}

TEST(GeneratorsTest, GridJitterIsDeterministicAndKeepsTheBoundary) {
  const Mesh a = Grid(8, 6, 4.0, 3.0, 0.45, 3);
  const Mesh b = Grid(8, 6, 4.0, 3.0, 0.45, 3);
  const Mesh c = Grid(8, 6, 4.0, 3.0, 0.45, 4);
  EXPECT_EQ(a.positions(), b.positions());
  EXPECT_NE(a.positions(), c.positions());
  // Interior vertices move within jitter * cell; boundary vertices do not move.
  const Mesh flat = Grid(8, 6, 4.0, 3.0);
  for (int v = 0; v < a.num_vertices(); ++v) {
    const Vec3 d = a.position(v) - flat.position(v);
    if (a.IsBoundaryVertex(v)) {
      EXPECT_EQ(d, Vec3::Zero()) << v;
    } else {
      EXPECT_LE(std::abs(d.x()), 0.45 * 0.5) << v;
      EXPECT_LE(std::abs(d.y()), 0.45 * 0.5) << v;
      EXPECT_EQ(d.z(), 0) << v;
    }
  }
  EXPECT_NEAR(a.TotalArea(), 12.0, 1e-12);
  ExpectUpwardNormals(a);
  ExpectUpwardNormals(c);
}

TEST(GeneratorsTest, LShape) {
  const Mesh mesh = LShape(3, 2.0);
  const Topology topology = TopologyOf(mesh);
  EXPECT_EQ(topology.euler, 1);
  EXPECT_EQ(topology.boundary_loops, 1);
  EXPECT_EQ(topology.boundary_edges, 8 * 3);
  EXPECT_EQ(mesh.num_vertices(), 7 * 7 - 3 * 3);  // no unreferenced vertices
  EXPECT_EQ(mesh.num_faces(), 2 * 3 * 9);
  EXPECT_NEAR(mesh.TotalArea(), 3.0, 1e-12);
  ExpectUpwardNormals(mesh);
  // The re-entrant corner at (size/2, size/2) is a boundary vertex with an
  // interior angle of 3 pi / 2.
  int corner = -1;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.position(v) == Vec3(1, 1, 0)) corner = v;
  }
  ASSERT_NE(corner, -1);
  EXPECT_TRUE(mesh.IsBoundaryVertex(corner));
  EXPECT_NEAR(mesh.AngleSum(corner), 1.5 * kPi, 1e-12);
}

TEST(GeneratorsTest, SquareWithHole) {
  const Mesh mesh = SquareWithHole(6, 3.0);
  const Topology topology = TopologyOf(mesh);
  EXPECT_EQ(topology.euler, 0);
  EXPECT_EQ(topology.boundary_loops, 2);
  EXPECT_EQ(topology.boundary_edges, 4 * 6 + 4 * 2);
  EXPECT_EQ(topology.components, 1);
  EXPECT_EQ(mesh.num_vertices(), 7 * 7 - 1);
  EXPECT_NEAR(mesh.TotalArea(), 9.0 * 8 / 9, 1e-12);
  ExpectUpwardNormals(mesh);
  // The smallest case: one cell removed.
  EXPECT_EQ(TopologyOf(SquareWithHole(3, 1.0)).euler, 0);
}

TEST(GeneratorsTest, FoldedSheet) {
  const double angle = kPi / 3;
  const Mesh mesh = FoldedSheet(6, 4, 3.0, 2.0, angle);
  const Topology topology = TopologyOf(mesh);
  EXPECT_EQ(topology.euler, 1);
  EXPECT_EQ(topology.boundary_loops, 1);
  // Developable: area and edge lengths are those of the flat sheet.
  const Mesh flat = FoldedSheet(6, 4, 3.0, 2.0, 0.0);
  EXPECT_EQ(flat.positions(), Grid(6, 4, 3.0, 2.0).positions());
  EXPECT_NEAR(mesh.TotalArea(), 6.0, 1e-12);
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    EXPECT_NEAR(mesh.Length(h), flat.Length(h), 1e-12) << h;
  }
  // The far edge is lifted: x = 1.5 + 1.5 cos(angle), z = 1.5 sin(angle).
  EXPECT_NEAR(mesh.position(6).x(), 1.5 + 1.5 * std::cos(angle), 1e-12);
  EXPECT_NEAR(mesh.position(6).z(), 1.5 * std::sin(angle), 1e-12);
  // Interior vertices on the fold still have angle sum 2 pi.
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!mesh.IsBoundaryVertex(v)) {
      EXPECT_NEAR(mesh.AngleSum(v), 2 * kPi, 1e-12) << v;
    }
  }
}

TEST(GeneratorsTest, Cylinder) {
  const int n = 12;
  const Mesh mesh = Cylinder(n, 5, 0.5, 2.0);
  const Topology topology = TopologyOf(mesh);
  EXPECT_EQ(topology.euler, 0);
  EXPECT_EQ(topology.boundary_loops, 2);
  EXPECT_EQ(topology.boundary_edges, 2 * n);
  EXPECT_EQ(mesh.num_vertices(), n * 6);
  // Polyhedral area: n flat strips of width 2 r sin(pi / n).
  EXPECT_NEAR(mesh.TotalArea(), n * 2 * 0.5 * std::sin(kPi / n) * 2.0, 1e-12);
  EXPECT_NEAR(Cylinder(200, 5, 0.5, 2.0).TotalArea(), 2 * kPi * 0.5 * 2.0, 1e-3);
  // Developable: every interior angle sum is 2 pi.
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!mesh.IsBoundaryVertex(v)) {
      EXPECT_NEAR(mesh.AngleSum(v), 2 * kPi, 1e-12) << v;
    }
  }
  // Outward: each face normal points away from the axis.
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Triangle& t = mesh.face(f);
    const Vec3 c = (mesh.position(t[0]) + mesh.position(t[1]) + mesh.position(t[2])) / 3;
    const Vec3 normal = (mesh.position(t[1]) - mesh.position(t[0]))
                            .cross(mesh.position(t[2]) - mesh.position(t[0]));
    EXPECT_GT(normal.dot(Vec3(c.x(), c.y(), 0)), 0) << f;
  }
}

TEST(GeneratorsTest, Cube) {
  for (int n : {1, 3}) {
    SCOPED_TRACE(n);
    const Mesh mesh = Cube(n, 2.0);
    const Topology topology = TopologyOf(mesh);
    EXPECT_EQ(topology.euler, 2);
    EXPECT_EQ(topology.boundary_edges, 0);
    EXPECT_EQ(topology.components, 1);
    EXPECT_EQ(mesh.num_vertices(), 6 * n * n + 2);  // shared along the cube's edges
    EXPECT_EQ(mesh.num_faces(), 12 * n * n);
    EXPECT_NEAR(mesh.TotalArea(), 24.0, 1e-12);
    EXPECT_NEAR(SignedVolume(mesh), 8.0, 1e-12);
    EXPECT_EQ(mesh.BoundingBoxMin(), Vec3(0, 0, 0));
    EXPECT_EQ(mesh.BoundingBoxMax(), Vec3(2, 2, 2));
    // Cube corners: three right angles.
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      const Vec3& p = mesh.position(v);
      const int on_faces =
          (p.x() == 0 || p.x() == 2) + (p.y() == 0 || p.y() == 2) + (p.z() == 0 || p.z() == 2);
      const double expected = on_faces == 3 ? 1.5 * kPi : 2 * kPi;
      EXPECT_NEAR(mesh.AngleSum(v), expected, 1e-12) << v;
    }
  }
}

TEST(GeneratorsTest, Sphere) {
  for (int s : {0, 1, 3}) {
    SCOPED_TRACE(s);
    const double r = 1.5;
    const Mesh mesh = Sphere(s, r);
    const Topology topology = TopologyOf(mesh);
    EXPECT_EQ(topology.euler, 2);
    EXPECT_EQ(topology.boundary_edges, 0);
    EXPECT_EQ(mesh.num_faces(), 20 << (2 * s));
    EXPECT_EQ(mesh.num_vertices(), 10 * (1 << (2 * s)) + 2);
    for (const Vec3& p : mesh.positions()) EXPECT_NEAR(p.norm(), r, 1e-12);
    EXPECT_GT(SignedVolume(mesh), 0);
    // Inscribed polyhedron: area and volume below the sphere's, converging.
    EXPECT_LT(mesh.TotalArea(), 4 * kPi * r * r);
    EXPECT_LT(SignedVolume(mesh), 4.0 / 3 * kPi * r * r * r);
  }
  const Mesh fine = Sphere(4, 1.0);
  EXPECT_NEAR(fine.TotalArea(), 4 * kPi, 4 * kPi * 0.005);
  EXPECT_NEAR(SignedVolume(fine), 4.0 / 3 * kPi, 4.0 / 3 * kPi * 0.01);
}

TEST(GeneratorsTest, Torus) {
  const double R = 2.0, r = 0.5;
  const Mesh mesh = Torus(48, 24, R, r);
  const Topology topology = TopologyOf(mesh);
  EXPECT_EQ(topology.euler, 0);
  EXPECT_EQ(topology.boundary_edges, 0);
  EXPECT_EQ(topology.components, 1);
  EXPECT_EQ(mesh.num_vertices(), 48 * 24);
  EXPECT_NEAR(mesh.TotalArea(), 4 * kPi * kPi * R * r, 4 * kPi * kPi * R * r * 0.01);
  EXPECT_GT(SignedVolume(mesh), 0);
  EXPECT_NEAR(SignedVolume(mesh), 2 * kPi * kPi * R * r * r, 2 * kPi * kPi * R * r * r * 0.02);
}

TEST(GeneratorsTest, DoubleTorus) {
  for (int resolution : {1, 2, 4}) {
    SCOPED_TRACE(resolution);
    const double size = 5.0;  // slab 5 x 3 x 1 with two 1 x 1 tunnels
    const Mesh mesh = DoubleTorus(resolution, size);
    const Topology topology = TopologyOf(mesh);
    EXPECT_EQ(topology.euler, -2);  // genus 2
    EXPECT_EQ(topology.boundary_edges, 0);
    EXPECT_EQ(topology.components, 1);
    // Top and bottom 2 x (15 - 2), outer wall 16 x 1, tunnel walls 2 x 4 x 1.
    EXPECT_NEAR(mesh.TotalArea(), 50.0, 1e-9);
    EXPECT_NEAR(SignedVolume(mesh), 13.0, 1e-9);
    EXPECT_NEAR((mesh.BoundingBoxMax() - mesh.BoundingBoxMin()).x(), size, 1e-12);
    for (int v = 0; v < mesh.num_vertices(); ++v) EXPECT_TRUE(mesh.IsReferenced(v));
  }
}

TEST(GeneratorsTest, SplitFacesInFourKeepsTheSurface) {
  for (const Mesh& mesh : {Torus(12, 8, 2.0, 0.5), SquareWithHole(6, 3.0)}) {
    SCOPED_TRACE(mesh.name());
    const Topology before = TopologyOf(mesh);
    const Mesh split = SplitFacesInFour(mesh, 2);
    const Topology after = TopologyOf(split);
    EXPECT_EQ(split.num_faces(), 16 * mesh.num_faces());
    EXPECT_EQ(after.euler, before.euler);
    EXPECT_EQ(after.components, before.components);
    EXPECT_EQ(after.boundary_loops, before.boundary_loops);
    EXPECT_EQ(after.boundary_edges, 4 * before.boundary_edges);
    EXPECT_NEAR(split.TotalArea(), mesh.TotalArea(), 1e-12 * mesh.TotalArea());
    for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
      EXPECT_EQ(split.position(v), mesh.position(v));
    }
  }
  EXPECT_EQ(SplitFacesInFour(Cube(2, 1.0), 0).num_faces(), Cube(2, 1.0).num_faces());
}

TEST(GeneratorsTest, TwoComponents) {
  const Mesh mesh = TwoComponents(4);
  const Topology topology = TopologyOf(mesh);
  EXPECT_EQ(topology.components, 2);
  EXPECT_EQ(topology.euler, 2);  // two disks
  EXPECT_EQ(topology.boundary_loops, 2);
  EXPECT_NEAR(mesh.TotalArea(), 2.0, 1e-12);
  EXPECT_EQ(mesh.BoundingBoxMin(), Vec3(0, 0, 0));
  EXPECT_EQ(mesh.BoundingBoxMax(), Vec3(3, 1, 0));
  ExpectUpwardNormals(mesh);
  // Vertices of the first grid lie in [0,1], of the second in [2,3].
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    EXPECT_EQ(mesh.VertexComponent(v), mesh.position(v).x() <= 1 ? 0 : 1) << v;
  }
}

TEST(GeneratorsTest, Deterministic) {
  EXPECT_EQ(DoubleTorus(2, 1.0).faces(), DoubleTorus(2, 1.0).faces());
  EXPECT_EQ(Sphere(2, 1.0).positions(), Sphere(2, 1.0).positions());
}

TEST(GeneratorsDeathTest, BadParametersAbort) {
  EXPECT_DEATH(Grid(0, 1, 1.0, 1.0), "Grid: nx and ny must be >= 1");
  EXPECT_DEATH(SquareWithHole(4, 1.0), "multiple of 3");
  EXPECT_DEATH(FoldedSheet(3, 2, 1.0, 1.0, 0.5), "nx must be even");
  EXPECT_DEATH(Grid(2, 2, 1.0, 1.0, 0.5), "jitter");
}

}  // namespace
}  // namespace geodex::mesh::gen
