#include "core/mesh/mesh.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::mesh {
namespace {

using ::testing::HasSubstr;

constexpr double kPi = std::numbers::pi;

// The unit square split along its diagonal 0-2:
//   3---2
//   | / |
//   0---1
std::vector<Vec3> SquarePositions() { return {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}; }

// A fan of `n` triangles around vertex 0 at the origin; closed (a disk with an
// interior centre) when `closed`, else missing the last triangle.
Mesh Fan(int n, bool closed) {
  std::vector<Vec3> positions = {{0, 0, 0}};
  std::vector<Triangle> faces;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * kPi * k / n;
    positions.push_back({std::cos(a), std::sin(a), 0});
  }
  for (int k = 0; k < (closed ? n : n - 1); ++k) faces.push_back({0, 1 + k, 1 + (k + 1) % n});
  return *Mesh::Create(positions, faces, "fan");
}

absl::Status CreateStatus(std::vector<Vec3> positions, std::vector<Triangle> faces) {
  return Mesh::Create(std::move(positions), std::move(faces), "test.obj").status();
}

TEST(MeshTest, SquareCountsAndTwins) {
  absl::StatusOr<Mesh> mesh = Mesh::Create(SquarePositions(), {{0, 1, 2}, {0, 2, 3}}, "square");
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_EQ(mesh->num_vertices(), 4);
  EXPECT_EQ(mesh->num_faces(), 2);
  EXPECT_EQ(mesh->num_halfedges(), 6);
  EXPECT_EQ(mesh->num_boundary_edges(), 4);
  EXPECT_EQ(mesh->name(), "square");
  // Half-edge 2 of face 0 runs 2->0; half-edge 3 of face 1 runs 0->2.
  EXPECT_EQ(mesh->Origin(2), 2);
  EXPECT_EQ(mesh->Dest(2), 0);
  EXPECT_EQ(mesh->Opposite(2), 1);
  EXPECT_EQ(mesh->Twin(2), 3);
  EXPECT_EQ(mesh->Twin(3), 2);
  for (int h : {0, 1, 4, 5}) EXPECT_EQ(mesh->Twin(h), kNone) << h;
  EXPECT_DOUBLE_EQ(mesh->Length(2), std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(mesh->Length(0), 1.0);
  EXPECT_EQ(Mesh::Next(2), 0);
  EXPECT_EQ(Mesh::Prev(3), 5);
  EXPECT_EQ(Mesh::FaceOf(5), 1);
  EXPECT_DOUBLE_EQ(mesh->TotalArea(), 1.0);
  EXPECT_DOUBLE_EQ(mesh->Area(1), 0.5);
  EXPECT_DOUBLE_EQ(mesh->BoundingBoxDiagonal(), std::sqrt(2.0));
  for (int v = 0; v < 4; ++v) EXPECT_TRUE(mesh->IsBoundaryVertex(v)) << v;
  // Angle sums: corners 0 and 2 are split by the diagonal.
  EXPECT_NEAR(mesh->AngleSum(0), kPi / 2, 1e-15);
  EXPECT_NEAR(mesh->AngleSum(1), kPi / 2, 1e-15);
  EXPECT_EQ(mesh->num_components(), 1);
}

TEST(MeshTest, TwinsAreConsistentOnClosedMesh) {
  const Mesh mesh = gen::Sphere(1, 1.0);
  EXPECT_EQ(mesh.num_boundary_edges(), 0);
  for (int h = 0; h < mesh.num_halfedges(); ++h) {
    const int t = mesh.Twin(h);
    ASSERT_NE(t, kNone);
    EXPECT_EQ(mesh.Twin(t), h);
    EXPECT_EQ(mesh.Origin(t), mesh.Dest(h));
    EXPECT_EQ(mesh.Dest(t), mesh.Origin(h));
    EXPECT_DOUBLE_EQ(mesh.Length(t), mesh.Length(h));
  }
  for (int v = 0; v < mesh.num_vertices(); ++v) EXPECT_FALSE(mesh.IsBoundaryVertex(v));
}

TEST(MeshTest, OutgoingIsCounterClockwiseFanOnInteriorVertex) {
  const Mesh mesh = Fan(6, /*closed=*/true);
  const std::span<const int32_t> out = mesh.Outgoing(0);
  ASSERT_EQ(out.size(), 6u);
  EXPECT_FALSE(mesh.IsBoundaryVertex(0));
  double previous_angle =
      std::atan2(mesh.position(mesh.Dest(out[0])).y(), mesh.position(mesh.Dest(out[0])).x());
  for (size_t k = 0; k < out.size(); ++k) {
    EXPECT_EQ(mesh.Origin(out[k]), 0);
    // The next outgoing half-edge is the twin of this face's incoming one.
    EXPECT_EQ(out[(k + 1) % out.size()], mesh.Twin(Mesh::Prev(out[k])));
    if (k > 0) {
      const Vec3& d = mesh.position(mesh.Dest(out[k]));
      double angle = std::atan2(d.y(), d.x());
      while (angle < previous_angle) angle += 2 * kPi;
      EXPECT_NEAR(angle - previous_angle, kPi / 3, 1e-12) << "counter-clockwise by 60 degrees";
      previous_angle = angle;
    }
  }
  // Flat interior vertex: angle sum 2 pi.
  EXPECT_NEAR(mesh.AngleSum(0), 2 * kPi, 1e-12);
}

TEST(MeshTest, OutgoingStartsAtBoundaryOnBoundaryVertex) {
  const Mesh mesh = Fan(6, /*closed=*/false);
  const std::span<const int32_t> out = mesh.Outgoing(0);
  ASSERT_EQ(out.size(), 5u);
  EXPECT_TRUE(mesh.IsBoundaryVertex(0));
  // The first outgoing half-edge has no clockwise neighbour; the last face's
  // incoming half-edge has no counter-clockwise one.
  EXPECT_EQ(mesh.Twin(out.front()), kNone);
  EXPECT_EQ(mesh.Twin(Mesh::Prev(out.back())), kNone);
  EXPECT_EQ(mesh.Dest(out.front()), 1);
  for (size_t k = 0; k + 1 < out.size(); ++k) {
    EXPECT_EQ(out[k + 1], mesh.Twin(Mesh::Prev(out[k])));
  }
  EXPECT_NEAR(mesh.AngleSum(0), 5 * kPi / 3, 1e-12);
}

TEST(MeshTest, AngleSumIsTwoPiOnFlatInteriorVertices) {
  const Mesh mesh = gen::Grid(6, 5, 3.0, 2.0, /*jitter=*/0.3, /*seed=*/7);
  int interior = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.IsBoundaryVertex(v)) continue;
    ++interior;
    EXPECT_NEAR(mesh.AngleSum(v), 2 * kPi, 1e-12) << v;
  }
  EXPECT_EQ(interior, 5 * 4);
}

TEST(MeshTest, ComponentsAndUnreferencedVertices) {
  // Two triangles sharing nothing, and vertex 6 used by no face.
  std::vector<Vec3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 0, 0},
                                 {6, 0, 0}, {5, 1, 0}, {9, 9, 9}};
  absl::StatusOr<Mesh> mesh = Mesh::Create(positions, {{0, 1, 2}, {3, 4, 5}});
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_EQ(mesh->num_components(), 2);
  EXPECT_NE(mesh->FaceComponent(0), mesh->FaceComponent(1));
  EXPECT_EQ(mesh->VertexComponent(1), mesh->FaceComponent(0));
  EXPECT_EQ(mesh->VertexComponent(4), mesh->FaceComponent(1));
  EXPECT_EQ(mesh->VertexComponent(6), kNone);
  EXPECT_FALSE(mesh->IsReferenced(6));
  EXPECT_TRUE(mesh->Outgoing(6).empty());
  EXPECT_FALSE(mesh->IsBoundaryVertex(6));
  // The bounding box ignores unreferenced vertices.
  EXPECT_EQ(mesh->BoundingBoxMax(), Vec3(6, 1, 0));
  EXPECT_EQ(mesh->BoundingBoxMin(), Vec3(0, 0, 0));
}

TEST(MeshTest, ComponentsOfGeneratedMesh) {
  const Mesh mesh = gen::TwoComponents(3);
  EXPECT_EQ(mesh.num_components(), 2);
  std::set<int32_t> seen;
  for (int f = 0; f < mesh.num_faces(); ++f) seen.insert(mesh.FaceComponent(f));
  EXPECT_EQ(seen, (std::set<int32_t>{0, 1}));
}

// --- Mesh::Create errors: one test per class. --------------------------------

TEST(MeshCreateErrorTest, NoFaces) {
  const absl::Status status = CreateStatus(SquarePositions(), {});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), HasSubstr("test.obj: mesh has no faces"));
}

TEST(MeshCreateErrorTest, IndexOutOfRange) {
  for (int bad : {4, -1}) {
    const absl::Status status = CreateStatus(SquarePositions(), {{0, 1, 2}, {0, 2, bad}});
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(std::string(status.message()),
                HasSubstr(absl::StrCat("face 1 references vertex ", bad, ", out of range [0, 4)")));
  }
}

TEST(MeshCreateErrorTest, RepeatedIndexInFace) {
  const absl::Status status = CreateStatus(SquarePositions(), {{0, 1, 2}, {3, 2, 3}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), HasSubstr("face 1 repeats a vertex (3 2 3)"));
}

TEST(MeshCreateErrorTest, NanCoordinate) {
  std::vector<Vec3> positions = SquarePositions();
  positions[2].y() = std::numeric_limits<double>::quiet_NaN();
  const absl::Status status = CreateStatus(positions, {{0, 1, 2}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), HasSubstr("vertex 2 has a non-finite coordinate"));
}

TEST(MeshCreateErrorTest, InfCoordinate) {
  std::vector<Vec3> positions = SquarePositions();
  positions[1].z() = -std::numeric_limits<double>::infinity();
  const absl::Status status = CreateStatus(positions, {{0, 1, 2}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("vertex 1 has a non-finite coordinate (1, 0, -inf)"));
}

TEST(MeshCreateErrorTest, ZeroAreaFace) {
  // Collinear corners.
  std::vector<Vec3> positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
  absl::Status status = CreateStatus(positions, {{0, 3, 1}, {0, 1, 2}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), HasSubstr("face 1 (0 1 2) has zero area"));
  // Coincident corners.
  positions[2] = positions[1];
  status = CreateStatus(positions, {{0, 1, 2}});
  EXPECT_THAT(std::string(status.message()), HasSubstr("face 0 (0 1 2) has zero area"));
}

TEST(MeshCreateErrorTest, DuplicateFace) {
  // Same vertices in another order, even with the other orientation.
  const absl::Status status = CreateStatus(SquarePositions(), {{0, 1, 2}, {0, 2, 3}, {2, 1, 0}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("faces 0 and 2 are duplicates (vertices 0 1 2)"));
}

TEST(MeshCreateErrorTest, NonManifoldEdge) {
  // Three triangles on edge (0, 1).
  std::vector<Vec3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  const absl::Status status = CreateStatus(positions, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("non-manifold edge (0, 1) is shared by 3 faces (0, 1, 2)"));
}

TEST(MeshCreateErrorTest, InconsistentOrientation) {
  const absl::Status status = CreateStatus(SquarePositions(), {{0, 1, 2}, {0, 3, 2}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("faces 0 and 1 traverse edge (0, 2) in the same direction"));
}

TEST(MeshCreateErrorTest, NonManifoldVertexBowTie) {
  // Two triangles touching only at vertex 0.
  std::vector<Vec3> positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  const absl::Status status = CreateStatus(positions, {{0, 1, 2}, {0, 3, 4}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("test.obj: non-manifold vertex 0: its 2 faces form more than one fan"));
}

TEST(MeshCreateErrorTest, NonManifoldVertexTwoClosedFans) {
  // Two tetrahedra sharing only vertex 0: each fan around 0 is closed.
  std::vector<Vec3> positions = {{0, 0, 0},  {1, 0, 0},  {0, 1, 0}, {0, 0, 1},
                                 {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  auto tetra = [](int32_t a, int32_t b, int32_t c, int32_t d) {
    return std::vector<Triangle>{{a, c, b}, {a, b, d}, {a, d, c}, {b, c, d}};
  };
  std::vector<Triangle> faces = tetra(0, 1, 2, 3);
  for (const Triangle& t : tetra(0, 4, 5, 6)) faces.push_back(t);
  // Each tetrahedron alone is a valid closed mesh.
  ASSERT_TRUE(Mesh::Create(positions, tetra(0, 1, 2, 3)).ok());
  ASSERT_TRUE(Mesh::Create(positions, tetra(0, 4, 5, 6)).ok());
  const absl::Status status = CreateStatus(positions, faces);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("non-manifold vertex 0: its 6 faces form more than one fan"));
}

TEST(MeshCreateErrorTest, UnreferencedVerticesAndSeveralComponentsAreAccepted) {
  std::vector<Vec3> positions = SquarePositions();
  for (const Vec3& p : SquarePositions()) positions.push_back(p + Vec3(3, 0, 0));
  positions.push_back({100, 100, 100});  // unreferenced
  absl::StatusOr<Mesh> mesh = Mesh::Create(positions, {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}});
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_EQ(mesh->num_components(), 2);
  EXPECT_FALSE(mesh->IsReferenced(8));
}

// --- Surface points. ---------------------------------------------------------

TEST(SurfacePointTest, PositionOf) {
  const Mesh mesh = *Mesh::Create(SquarePositions(), {{0, 1, 2}, {0, 2, 3}});
  const SurfacePoint p{1, {0.5, 0.25, 0.25}};
  EXPECT_TRUE(PositionOf(mesh, p).isApprox(Vec3(0.25, 0.5, 0)));
}

TEST(SurfacePointTest, ValidateSurfacePointErrors) {
  const Mesh mesh = *Mesh::Create(SquarePositions(), {{0, 1, 2}, {0, 2, 3}});
  EXPECT_TRUE(ValidateSurfacePoint(mesh, {1, {0.2, 0.3, 0.5}}).ok());
  // Slightly negative weights within the tolerance are accepted.
  EXPECT_TRUE(ValidateSurfacePoint(mesh, {0, {-1e-9, 0.5, 0.5 + 1e-9}}).ok());

  absl::Status status = ValidateSurfacePoint(mesh, {2, {1, 0, 0}});
  EXPECT_EQ(status.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(std::string(status.message()), HasSubstr("face id 2 out of range [0, 2)"));
  status = ValidateSurfacePoint(mesh, {kNone, {1, 0, 0}});
  EXPECT_EQ(status.code(), absl::StatusCode::kOutOfRange);

  status = ValidateSurfacePoint(mesh, {0, {std::numeric_limits<double>::quiet_NaN(), 0.5, 0.5}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("barycentric weight 0 of face 0 is not finite"));

  status = ValidateSurfacePoint(mesh, {1, {0.5, -0.25, 0.75}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("barycentric weight 1 of face 1 is negative (-0.25)"));

  status = ValidateSurfacePoint(mesh, {1, {0.5, 0.5, 0.5}});
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()),
              HasSubstr("barycentric weights of face 1 sum to 1.5, not 1"));

  // The face-count form (a loaded index) answers the same.
  EXPECT_TRUE(ValidateSurfacePoint(2, {1, {0.2, 0.3, 0.5}}).ok());
  EXPECT_EQ(ValidateSurfacePoint(2, {1, {0.5, 0.5, 0.5}}),
            ValidateSurfacePoint(mesh, {1, {0.5, 0.5, 0.5}}));
  EXPECT_EQ(ValidateSurfacePoint(2, {2, {1, 0, 0}}), ValidateSurfacePoint(mesh, {2, {1, 0, 0}}));
}

TEST(SurfacePointTest, VertexPoint) {
  std::vector<Vec3> positions = SquarePositions();
  positions.push_back({7, 7, 7});  // unreferenced vertex 4
  const Mesh mesh = *Mesh::Create(positions, {{0, 1, 2}, {0, 2, 3}});
  for (int v = 0; v < 4; ++v) {
    absl::StatusOr<SurfacePoint> p = VertexPoint(mesh, v);
    ASSERT_TRUE(p.ok()) << p.status();
    EXPECT_TRUE(ValidateSurfacePoint(mesh, *p).ok());
    EXPECT_EQ(PositionOf(mesh, *p), mesh.position(v));
  }
  absl::StatusOr<SurfacePoint> p = VertexPoint(mesh, 5);
  EXPECT_EQ(p.status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(std::string(p.status().message()), HasSubstr("vertex id 5 out of range [0, 5)"));
  p = VertexPoint(mesh, -1);
  EXPECT_EQ(p.status().code(), absl::StatusCode::kOutOfRange);
  p = VertexPoint(mesh, 4);
  EXPECT_EQ(p.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(p.status().message()),
              HasSubstr("vertex 4 is not referenced by any face"));
}

}  // namespace
}  // namespace geodex::mesh
