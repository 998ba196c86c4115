#include "core/mesh/long_edge_split.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::mesh {
namespace {

constexpr int32_t kNoCap = std::numeric_limits<int32_t>::max();

Mesh MustCreate(std::vector<Vec3> positions, std::vector<Triangle> faces, std::string name,
                const MeshOptions& options = {}) {
  absl::StatusOr<Mesh> mesh =
      Mesh::Create(std::move(positions), std::move(faces), std::move(name), options);
  EXPECT_TRUE(mesh.ok()) << mesh.status();
  return *std::move(mesh);
}

// One right triangle, legs 2 and 1: every edge on the boundary.
Mesh SingleFace() { return MustCreate({{0, 0, 0}, {2, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}, "face"); }

// The unit square in two faces along the diagonal 0-2.
Mesh TwoFaceSquare() {
  return MustCreate({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}, "square");
}

int32_t NumEdges(const Mesh& mesh) {
  return (mesh.num_halfedges() + mesh.num_boundary_edges()) / 2;
}

int32_t EulerCharacteristic(const Mesh& mesh) {
  return mesh.num_vertices() - NumEdges(mesh) + mesh.num_faces();
}

double LongestEdge(const Mesh& mesh) {
  double longest = 0;
  for (int32_t h = 0; h < mesh.num_halfedges(); ++h) longest = std::max(longest, mesh.Length(h));
  return longest;
}

double SmallestAngle(const Mesh& mesh) {
  double smallest = std::numbers::pi;
  for (int32_t h = 0; h < mesh.num_halfedges(); ++h) {
    // The angle at the origin of h, between h and the previous half-edge.
    const Vec3 u = mesh.position(mesh.Dest(h)) - mesh.position(mesh.Origin(h));
    const Vec3 w = mesh.position(mesh.Opposite(h)) - mesh.position(mesh.Origin(h));
    smallest = std::min(smallest, std::atan2(u.cross(w).norm(), u.dot(w)));
  }
  return smallest;
}

Vec3 Normal(const Vec3& a, const Vec3& b, const Vec3& c) { return (b - a).cross(c - a); }

// Everything a long-edge split keeps, whether or not the cap stopped it.
void ExpectSameSurface(const Mesh& input, const LongEdgeSplit& r) {
  const Mesh& out = r.mesh;
  const double tolerance = 1e-12 * input.BoundingBoxDiagonal();
  EXPECT_EQ(out.name(), input.name());
  ASSERT_EQ(out.num_vertices(), input.num_vertices() + r.new_vertices);
  for (int32_t v = 0; v < input.num_vertices(); ++v) {
    EXPECT_EQ(out.position(v), input.position(v)) << "input vertex " << v;
  }
  ASSERT_EQ(r.parent.size(), static_cast<size_t>(out.num_faces()));
  ASSERT_EQ(r.weights.size(), static_cast<size_t>(out.num_faces()));
  EXPECT_GE(out.num_faces(), input.num_faces());

  EXPECT_NEAR(out.TotalArea(), input.TotalArea(), 1e-12 * input.TotalArea());
  EXPECT_EQ(out.num_components(), input.num_components());
  EXPECT_EQ(EulerCharacteristic(out), EulerCharacteristic(input));
  // Each midpoint on the boundary split one boundary edge in two.
  int32_t boundary_midpoints = 0;
  for (int32_t v = input.num_vertices(); v < out.num_vertices(); ++v) {
    if (out.IsBoundaryVertex(v)) ++boundary_midpoints;
  }
  EXPECT_EQ(out.num_boundary_edges(), input.num_boundary_edges() + boundary_midpoints);

  std::vector<double> area_in_parent(input.num_faces(), 0.0);
  for (int32_t f = 0; f < out.num_faces(); ++f) {
    const int32_t p = r.parent[f];
    ASSERT_GE(p, 0) << "face " << f;
    ASSERT_LT(p, input.num_faces()) << "face " << f;
    if (f < input.num_faces()) {
      EXPECT_EQ(p, f) << "face " << f << " keeps its id";
    }
    area_in_parent[p] += out.Area(f);
    const Triangle& pt = input.face(p);
    std::array<Vec3, 3> corner;
    for (int i = 0; i < 3; ++i) {
      const std::array<double, 3>& w = r.weights[f][i];
      double sum = 0;
      for (int t = 0; t < 3; ++t) {
        EXPECT_GE(w[t], 0.0) << "face " << f << " corner " << i;
        EXPECT_LE(w[t], 1.0) << "face " << f << " corner " << i;
        sum += w[t];
      }
      EXPECT_NEAR(sum, 1.0, 1e-15) << "face " << f << " corner " << i;
      const Vec3 at = w[0] * input.position(pt[0]) + w[1] * input.position(pt[1]) +
                      w[2] * input.position(pt[2]);
      corner[i] = out.position(out.face(f)[i]);
      EXPECT_LE((at - corner[i]).norm(), tolerance) << "face " << f << " corner " << i;
    }
    if (input.Area(p) > 0) {
      const Vec3 parent_normal =
          Normal(input.position(pt[0]), input.position(pt[1]), input.position(pt[2])).normalized();
      const Vec3 normal = Normal(corner[0], corner[1], corner[2]).normalized();
      EXPECT_NEAR(normal.dot(parent_normal), 1.0, 1e-9) << "face " << f << " parent " << p;
    }
  }
  for (int32_t p = 0; p < input.num_faces(); ++p) {
    EXPECT_NEAR(area_in_parent[p], input.Area(p), 1e-12 * input.TotalArea()) << "parent " << p;
  }
}

// Refines without a cap and checks that no edge is left too long.
void ExpectRefinedTo(const Mesh& input, double max_edge_length) {
  SCOPED_TRACE(input.name());
  absl::StatusOr<LongEdgeSplit> r = SplitLongEdges(input, max_edge_length, kNoCap);
  ASSERT_TRUE(r.ok()) << r.status();
  ExpectSameSurface(input, *r);
  EXPECT_GT(r->new_vertices, 0);
  EXPECT_LE(LongestEdge(r->mesh), max_edge_length);
  // Longest-edge bisection's bound (Rosenberg and Stenger).
  EXPECT_GE(SmallestAngle(r->mesh), 0.5 * SmallestAngle(input) - 1e-12);
}

TEST(RefineLongEdgesTest, ClosedMeshesEndWithNoLongEdge) {
  const Mesh sphere = gen::Sphere(1, 1.0);
  ExpectRefinedTo(sphere, 0.5 * LongestEdge(sphere));
  ExpectRefinedTo(sphere, 0.1);
  ExpectRefinedTo(gen::Cube(1, 1.0), 0.3);
  ExpectRefinedTo(gen::Torus(8, 4, 2.0, 0.5), 0.2);
}

TEST(RefineLongEdgesTest, MeshesWithBoundaryEndWithNoLongEdge) {
  ExpectRefinedTo(SingleFace(), 0.3);
  ExpectRefinedTo(TwoFaceSquare(), 0.25);
  ExpectRefinedTo(gen::Grid(3, 2, 3.0, 1.0, 0.3), 0.4);
  ExpectRefinedTo(gen::SquareWithHole(3, 3.0), 0.5);
  ExpectRefinedTo(gen::TwoComponents(2), 0.2);
}

TEST(RefineLongEdgesTest, CapIsHonouredExactly) {
  const Mesh sphere = gen::Sphere(1, 1.0);
  for (int32_t cap : {1, 7, 50}) {
    SCOPED_TRACE(cap);
    absl::StatusOr<LongEdgeSplit> r = SplitLongEdges(sphere, 0.1, cap);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->new_vertices, cap);
    EXPECT_EQ(r->mesh.num_vertices(), sphere.num_vertices() + cap);
    ExpectSameSurface(sphere, *r);
    EXPECT_GT(LongestEdge(r->mesh), 0.1);
  }
  absl::StatusOr<LongEdgeSplit> none = SplitLongEdges(sphere, 0.1, 0);
  ASSERT_TRUE(none.ok()) << none.status();
  EXPECT_EQ(none->new_vertices, 0);
  EXPECT_EQ(none->mesh.faces(), sphere.faces());
}

TEST(RefineLongEdgesTest, SplitsTheLongestEdgeFirstAndBothItsFaces) {
  absl::StatusOr<LongEdgeSplit> r = SplitLongEdges(TwoFaceSquare(), 0.5, 1);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_EQ(r->new_vertices, 1);
  EXPECT_EQ(r->mesh.position(4), Vec3(0.5, 0.5, 0));  // the diagonal's midpoint
  ASSERT_EQ(r->mesh.num_faces(), 4);
  for (const Triangle& t : r->mesh.faces()) EXPECT_THAT(t, ::testing::Contains(4));
  EXPECT_FALSE(r->mesh.IsBoundaryVertex(4));
}

TEST(RefineLongEdgesTest, TiesAreBrokenByVertexIds) {
  // Every face diagonal of the cube has length sqrt(2); the first split is
  // the one with the lowest vertex ids.
  const Mesh cube = gen::Cube(1, 1.0);
  const double longest = LongestEdge(cube);
  std::pair<int32_t, int32_t> first = {cube.num_vertices(), cube.num_vertices()};
  int32_t ties = 0;
  for (int32_t h = 0; h < cube.num_halfedges(); ++h) {
    if (cube.Length(h) != longest || cube.Origin(h) > cube.Dest(h)) continue;
    ++ties;
    first = std::min(first, std::pair(cube.Origin(h), cube.Dest(h)));
  }
  ASSERT_GT(ties, 1);
  absl::StatusOr<LongEdgeSplit> r = SplitLongEdges(cube, 1.2, 1);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->mesh.position(cube.num_vertices()),
            Vec3(0.5 * (cube.position(first.first) + cube.position(first.second))));

  absl::StatusOr<LongEdgeSplit> again = SplitLongEdges(cube, 0.3, kNoCap);
  absl::StatusOr<LongEdgeSplit> once_more = SplitLongEdges(cube, 0.3, kNoCap);
  ASSERT_TRUE(again.ok() && once_more.ok());
  EXPECT_EQ(again->mesh.faces(), once_more->mesh.faces());
  EXPECT_EQ(again->mesh.positions(), once_more->mesh.positions());
}

TEST(RefineLongEdgesTest, ShortEdgesLeaveTheMeshUnchanged) {
  for (const Mesh& mesh : {gen::Torus(8, 4, 2.0, 0.5), SingleFace()}) {
    SCOPED_TRACE(mesh.name());
    absl::StatusOr<LongEdgeSplit> r = SplitLongEdges(mesh, LongestEdge(mesh), kNoCap);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->new_vertices, 0);
    EXPECT_EQ(r->mesh.positions(), mesh.positions());
    EXPECT_EQ(r->mesh.faces(), mesh.faces());
    ASSERT_EQ(r->parent.size(), static_cast<size_t>(mesh.num_faces()));
    for (int32_t f = 0; f < mesh.num_faces(); ++f) {
      EXPECT_EQ(r->parent[f], f);
      for (int i = 0; i < 3; ++i) {
        for (int t = 0; t < 3; ++t) EXPECT_EQ(r->weights[f][i][t], i == t ? 1.0 : 0.0);
      }
    }
  }
}

TEST(RefineLongEdgesTest, ZeroAreaFacesAreKept) {
  // A 2x2 square whose bottom edge 0-1 closes a zero-area face (0, 1, 4)
  // over the vertex 4 in its middle: splitting 0-1 puts a midpoint on 4.
  const Mesh mesh = MustCreate({{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {1, 0, 0}},
                               {{0, 4, 3}, {4, 1, 2}, {4, 2, 3}, {0, 1, 4}}, "sliver",
                               {.allow_zero_area_faces = true});
  absl::StatusOr<LongEdgeSplit> r = SplitLongEdges(mesh, 0.6, kNoCap);
  ASSERT_TRUE(r.ok()) << r.status();
  ExpectSameSurface(mesh, *r);
  EXPECT_LE(LongestEdge(r->mesh), 0.6);
}

TEST(RefineLongEdgesTest, InvalidArgumentsAreRefused) {
  const Mesh mesh = SingleFace();
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(SplitLongEdges(mesh, bad, kNoCap).status().code(), absl::StatusCode::kInvalidArgument)
        << bad;
  }
  EXPECT_EQ(SplitLongEdges(mesh, 0.5, -1).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace geodex::mesh
