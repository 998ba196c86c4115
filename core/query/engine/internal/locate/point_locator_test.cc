#include "core/query/engine/internal/locate/point_locator.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/index/face_bvh.h"
#include "core/index/face_bvh_testing.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

using mesh::Mesh;
using mesh::Vec3;

// The index's flattened mesh and BVH, and a locator over them.
struct Flat : index::testing::FlatMesh {
  using FlatMesh::FlatMesh;
  PointLocator Locator() const { return PointLocator(positions, faces, nodes, leaf_faces); }
};

// Closest distance from x to segment [a, b].
double SegmentDistance(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (x - (a + t * ab)).norm();
}

// Reference, independent of the locator's Ericson routine: project onto the
// face's plane; if the projection is inside, that is the closest point,
// otherwise the closest point lies on one of the three edges.
double TriangleDistance(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const Vec3 q = x - n * (n.dot(x - a) / n.squaredNorm());
  const double area = n.squaredNorm();
  const double wa = (c - b).cross(q - b).dot(n) / area;
  const double wb = (a - c).cross(q - c).dot(n) / area;
  const double wc = (b - a).cross(q - a).dot(n) / area;
  if (wa >= 0 && wb >= 0 && wc >= 0) return (x - q).norm();
  return std::min({SegmentDistance(x, a, b), SegmentDistance(x, b, c), SegmentDistance(x, c, a)});
}

double BruteForceDistance(const Mesh& mesh, const Vec3& x) {
  double best = std::numeric_limits<double>::infinity();
  for (const mesh::Triangle& f : mesh.faces()) {
    best = std::min(
        best, TriangleDistance(x, mesh.position(f[0]), mesh.position(f[1]), mesh.position(f[2])));
  }
  return best;
}

// Checks one query against brute force: same distance (1e-12 relative to
// max(distance, 1); the meshes are of unit size), valid weights that
// reproduce the closest point.
void ExpectMatchesBruteForce(const Mesh& mesh, const PointLocator& locator, const Vec3& x) {
  absl::StatusOr<LocatedPoint> located = locator.Locate(x);
  ASSERT_TRUE(located.ok()) << located.status();
  const double expected = BruteForceDistance(mesh, x);
  const double tolerance = 1e-12 * std::max(1.0, expected);
  EXPECT_NEAR(located->distance, expected, tolerance) << x.transpose();
  EXPECT_TRUE(mesh::ValidateSurfacePoint(mesh, located->point, 1e-14).ok()) << x.transpose();
  for (double w : located->point.w) EXPECT_GE(w, 0.0);
  EXPECT_NEAR((mesh::PositionOf(mesh, located->point) - x).norm(), located->distance, tolerance);
}

void CheckRandomPoints(const Mesh& mesh, uint64_t seed, int count) {
  const Flat flat(mesh);
  const PointLocator locator = flat.Locator();
  const Vec3 lo = mesh.BoundingBoxMin(), hi = mesh.BoundingBoxMax();
  const Vec3 centre = (lo + hi) / 2;
  const double size = mesh.BoundingBoxDiagonal();
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < count; ++i) {
    Vec3 x;
    switch (i % 4) {
      case 0: {  // in and around the bounding box
        for (int k = 0; k < 3; ++k) x[k] = lo[k] + (hi[k] - lo[k]) * (2 * unit(random) - 0.5);
        break;
      }
      case 1:
      case 2: {  // close to the surface: a random surface point, slightly moved
        const int32_t f = static_cast<int32_t>(unit(random) * mesh.num_faces());
        double u = unit(random), v = unit(random);
        if (u + v > 1) u = 1 - u, v = 1 - v;
        const mesh::Triangle& t = mesh.face(f);
        const Vec3 p =
            (1 - u - v) * mesh.position(t[0]) + u * mesh.position(t[1]) + v * mesh.position(t[2]);
        const double scale = size * (i % 4 == 1 ? 1e-3 : 1e-8);
        x = p + scale * Vec3(normal(random), normal(random), normal(random));
        break;
      }
      default: {  // far away
        x = centre + 100 * size * Vec3(normal(random), normal(random), normal(random));
        break;
      }
    }
    ExpectMatchesBruteForce(mesh, locator, x);
    if (::testing::Test::HasFailure()) return;  // one report is enough
  }
}

TEST(PointLocatorTest, SphereMatchesBruteForce) {
  CheckRandomPoints(mesh::gen::Sphere(2, 1.0), 1, 2000);
}

TEST(PointLocatorTest, CubeMatchesBruteForce) {
  CheckRandomPoints(mesh::gen::Cube(3, 2.0), 2, 2000);
}

TEST(PointLocatorTest, TorusMatchesBruteForce) {
  CheckRandomPoints(mesh::gen::Torus(24, 12, 1.0, 0.3), 3, 1000);
}

TEST(PointLocatorTest, ClosedFormAboveAGrid) {
  const Mesh grid = mesh::gen::Grid(4, 4, 1.0, 1.0);
  const Flat flat(grid);
  absl::StatusOr<LocatedPoint> located = flat.Locator().Locate(Vec3(0.3, 0.7, 2.0));
  ASSERT_TRUE(located.ok()) << located.status();
  EXPECT_NEAR(located->distance, 2.0, 1e-15);
  EXPECT_LT((mesh::PositionOf(grid, located->point) - Vec3(0.3, 0.7, 0)).norm(), 1e-15);
  // Beyond the corner (1, 1, 0): the corner itself.
  located = flat.Locator().Locate(Vec3(2, 3, 0));
  ASSERT_TRUE(located.ok()) << located.status();
  EXPECT_DOUBLE_EQ(located->distance, std::sqrt(5.0));
  EXPECT_EQ(mesh::PositionOf(grid, located->point), Vec3(1, 1, 0));
}

// At a vertex: distance exactly 0, all weight on that vertex, and of the faces
// around it (all at distance 0) the lowest id.
TEST(PointLocatorTest, PointsExactlyOnVertices) {
  for (const Mesh& mesh :
       {mesh::gen::Sphere(2, 1.0), mesh::gen::Cube(3, 2.0), mesh::gen::Grid(5, 3, 1.0, 0.5)}) {
    const Flat flat(mesh);
    const PointLocator locator = flat.Locator();
    for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
      absl::StatusOr<LocatedPoint> located = locator.Locate(mesh.position(v));
      ASSERT_TRUE(located.ok()) << located.status();
      EXPECT_EQ(located->distance, 0.0) << mesh.name() << " vertex " << v;
      int32_t lowest = std::numeric_limits<int32_t>::max();
      for (int32_t h : mesh.Outgoing(v)) lowest = std::min(lowest, Mesh::FaceOf(h));
      EXPECT_EQ(located->point.face, lowest) << mesh.name() << " vertex " << v;
      const mesh::Triangle& f = mesh.face(located->point.face);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(located->point.w[k], f[k] == v ? 1.0 : 0.0);
    }
  }
}

TEST(PointLocatorTest, PointsExactlyOnEdges) {
  for (const Mesh& mesh : {mesh::gen::Sphere(2, 1.0), mesh::gen::Cube(3, 2.0)}) {
    const Flat flat(mesh);
    const PointLocator locator = flat.Locator();
    for (int32_t h = 0; h < mesh.num_halfedges(); ++h) {
      for (double t : {0.5, 0.25}) {
        const Vec3 x = (1 - t) * mesh.position(mesh.Origin(h)) + t * mesh.position(mesh.Dest(h));
        absl::StatusOr<LocatedPoint> located = locator.Locate(x);
        ASSERT_TRUE(located.ok()) << located.status();
        EXPECT_LT(located->distance, 1e-15) << mesh.name() << " half-edge " << h;
        const int32_t f = located->point.face;
        EXPECT_TRUE(f == Mesh::FaceOf(h) || f == Mesh::FaceOf(mesh.Twin(h)))
            << mesh.name() << " half-edge " << h << " face " << f;
        EXPECT_LT((mesh::PositionOf(mesh, located->point) - x).norm(), 1e-15);
      }
    }
  }
}

TEST(PointLocatorTest, NonFiniteQueryIsInvalidArgument) {
  const Flat flat(mesh::gen::Sphere(1, 1.0));
  const PointLocator locator = flat.Locator();
  const double inf = std::numeric_limits<double>::infinity();
  for (const Vec3& x : {Vec3(std::nan(""), 0, 0), Vec3(0, inf, 0), Vec3(0, 0, -inf)}) {
    EXPECT_EQ(locator.Locate(x).status().code(), absl::StatusCode::kInvalidArgument);
  }
}

TEST(PointLocatorTest, EmptyHierarchyIsFailedPrecondition) {
  std::vector<index::BvhNode> nodes;
  std::vector<int32_t> leaf_faces;
  index::BuildFaceBvh({}, {}, &nodes, &leaf_faces);
  EXPECT_TRUE(nodes.empty());
  EXPECT_TRUE(leaf_faces.empty());
  const PointLocator locator({}, {}, nodes, leaf_faces);
  EXPECT_EQ(locator.Locate(Vec3::Zero()).status().code(), absl::StatusCode::kFailedPrecondition);
}

// The locator works in place on a validated index's spans.
TEST(PointLocatorTest, WorksOnIndexSpans) {
  const Mesh mesh = mesh::gen::Cube(2, 1.0);
  const Flat flat(mesh);
  index::IndexData d;
  d.positions = flat.positions;
  d.faces = flat.faces;
  for (int32_t h = 0; h < mesh.num_halfedges(); ++h) d.twins.push_back(mesh.Twin(h));
  d.vertices.resize(mesh.num_vertices());
  for (index::VertexRecord& r : d.vertices) {
    r = index::VertexRecord{.triangle = -1, .distance = {}};
  }
  d.bvh_nodes = flat.nodes;
  d.bvh_faces = flat.leaf_faces;
  absl::StatusOr<std::string> bytes = index::SerializeIndex(d);
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  absl::StatusOr<std::shared_ptr<const index::Index>> idx = index::Index::FromBytes(*bytes);
  ASSERT_TRUE(idx.ok()) << idx.status();
  const PointLocator locator((*idx)->positions(), (*idx)->faces(), (*idx)->bvh_nodes(),
                             (*idx)->bvh_faces());
  absl::StatusOr<LocatedPoint> located = locator.Locate(Vec3(0.5, 0.5, 3.0));
  ASSERT_TRUE(located.ok()) << located.status();
  EXPECT_NEAR(located->distance, 2.0, 1e-15);
}

}  // namespace
}  // namespace geodex::query
