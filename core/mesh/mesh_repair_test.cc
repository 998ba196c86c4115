#include "core/mesh/mesh_repair.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "core/mesh/broken_meshes_testing.h"
#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::mesh {
namespace {

using testing::AddTriangle;
using testing::AddVertex;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using testing::RawOf;

RepairOptions Strict() {
  RepairOptions options;
  options.strict = true;
  return options;
}

// The input vertex of internal vertex v.
int32_t InputVertex(const RepairedMesh& r, int32_t v) {
  return v < r.maps.num_input_vertices ? v : r.maps.vertex_copies[v - r.maps.num_input_vertices];
}

// Every input triangle's corners, through the maps, are its own vertices.
void ExpectMapsRecoverInput(const RawMesh& raw, const RepairedMesh& r) {
  for (size_t f = 0; f < raw.triangles.size(); ++f) {
    const InputFace in =
        r.maps.faces.empty() ? InputFace{static_cast<int32_t>(f)} : r.maps.faces[f];
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(InputVertex(r, r.mesh.face(in.face)[in.corner[i]]), raw.triangles[f][i])
          << "input face " << f << " corner " << i;
    }
  }
}

TEST(MeshRepairTest, ValidMeshIsUnchanged) {
  const Mesh sphere = gen::Sphere(2, 1.0);
  const RawMesh raw = RawOf(sphere, "sphere");
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_TRUE(r->maps.identity());
  EXPECT_FALSE(r->report.changed());
  EXPECT_EQ(r->mesh.faces(), sphere.faces());
  EXPECT_EQ(r->report.Summary(),
            "0 non-manifold vertices split (0 copies), 0 non-manifold edges cut (0 copies), 0 "
            "duplicate faces dropped, 0 faces re-oriented, 0 unreferenced vertices ignored, 0 "
            "zero-area faces and 0 slivers kept");
  EXPECT_TRUE(RepairMesh(raw, Strict()).ok());
}

TEST(MeshRepairTest, DuplicateFacesAreDroppedAndMapToTheirTwin) {
  const Mesh sphere = gen::Sphere(2, 1.0);
  RawMesh raw = RawOf(sphere, "sphere");
  const Triangle t = raw.triangles[7];
  AddTriangle(&raw, {t[1], t[2], t[0]});  // the same face, rotated: input face 320
  AddTriangle(&raw, {t[0], t[2], t[1]});  // reversed: input face 321
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.duplicate_faces, 2);
  EXPECT_EQ(r->report.reoriented_faces, 0);
  EXPECT_EQ(r->mesh.num_faces(), sphere.num_faces());
  ASSERT_EQ(r->maps.faces.size(), raw.triangles.size());
  EXPECT_FALSE(r->maps.faces[7].dropped);
  for (int32_t f : {320, 321}) {
    EXPECT_TRUE(r->maps.faces[f].dropped);
    EXPECT_EQ(r->maps.faces[f].face, 7);
  }
  EXPECT_THAT(r->maps.faces[320].corner, ElementsAre(1, 2, 0));
  EXPECT_THAT(r->maps.faces[321].corner, ElementsAre(0, 2, 1));
  ExpectMapsRecoverInput(raw, *r);
  EXPECT_THAT(r->report.ToText(), HasSubstr("mesh_duplicate_faces_dropped = 2\n"));

  const absl::StatusOr<RepairedMesh> strict = RepairMesh(raw, Strict());
  ASSERT_FALSE(strict.ok());
  EXPECT_EQ(strict.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(strict.status().message(), HasSubstr("faces 7 and 320 are duplicates"));
}

TEST(MeshRepairTest, UnreferencedVerticesAreIgnored) {
  RawMesh raw = RawOf(gen::Grid(3, 3, 1, 1), "grid");
  AddVertex(&raw, Vec3(5, 5, 5));
  AddVertex(&raw, Vec3(6, 5, 5));
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.unreferenced_vertices, 2);
  EXPECT_FALSE(r->report.changed());
  EXPECT_TRUE(r->maps.identity());
  EXPECT_EQ(r->mesh.num_vertices(), 18);
  EXPECT_FALSE(r->mesh.IsReferenced(17));
  // Never refused: Mesh::Create always accepted them.
  absl::StatusOr<RepairedMesh> strict = RepairMesh(raw, Strict());
  ASSERT_TRUE(strict.ok()) << strict.status();
  EXPECT_EQ(strict->report.unreferenced_vertices, 2);
}

TEST(MeshRepairTest, BowtieVertexIsSplitIntoOneCopyPerFan) {
  const RawMesh raw = testing::Bowtie();
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.nonmanifold_vertices, 1);
  EXPECT_EQ(r->report.vertex_copies, 2);
  EXPECT_EQ(r->mesh.num_vertices(), 6);
  EXPECT_THAT(r->maps.vertex_copies, ElementsAre(0));
  EXPECT_EQ(r->mesh.face(0)[0], 0);  // the first fan keeps the id
  EXPECT_EQ(r->mesh.face(1)[0], 5);
  EXPECT_EQ(r->mesh.num_components(), 2);
  EXPECT_EQ(r->mesh.position(5), r->mesh.position(0));
  ExpectMapsRecoverInput(raw, *r);
  const absl::StatusOr<RepairedMesh> strict = RepairMesh(raw, Strict());
  ASSERT_FALSE(strict.ok());
  EXPECT_THAT(strict.status().message(), HasSubstr("non-manifold vertex 0"));
}

TEST(MeshRepairTest, PyramidsTouchingAtTheApexBecomeTwoClosedSurfaces) {
  const RawMesh raw = testing::TwoPyramidsApexToApex();
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.nonmanifold_vertices, 1);
  EXPECT_EQ(r->report.vertex_copies, 2);
  EXPECT_EQ(r->report.reoriented_faces, 0);
  EXPECT_EQ(r->mesh.num_components(), 2);
  EXPECT_EQ(r->mesh.num_boundary_edges(), 0);
  EXPECT_THAT(r->report.Summary(), HasSubstr("1 non-manifold vertex split (2 copies)"));
  ExpectMapsRecoverInput(raw, *r);
  EXPECT_THAT(RepairMesh(raw, Strict()).status().message(), HasSubstr("non-manifold vertex 0"));
}

TEST(MeshRepairTest, CubesSharingAnEdgeEachKeepTheirOwnEdge) {
  const RawMesh raw = testing::TwoCubesSharingAnEdge();
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.nonmanifold_edges, 1);
  EXPECT_EQ(r->report.edge_copies, 2);
  EXPECT_EQ(r->report.nonmanifold_vertices, 2);  // the edge's ends
  EXPECT_EQ(r->report.vertex_copies, 4);
  EXPECT_EQ(r->report.reoriented_faces, 0);
  // Two closed cubes: no boundary, two parts, each of area 6.
  EXPECT_EQ(r->mesh.num_boundary_edges(), 0);
  EXPECT_EQ(r->mesh.num_components(), 2);
  EXPECT_EQ(r->mesh.num_vertices(), 16);
  EXPECT_NEAR(r->mesh.TotalArea(), 12, 1e-12);
  ExpectMapsRecoverInput(raw, *r);
  const absl::StatusOr<RepairedMesh> strict = RepairMesh(raw, Strict());
  ASSERT_FALSE(strict.ok());
  EXPECT_THAT(strict.status().message(),
              HasSubstr("non-manifold edge (3, 7) is shared by 4 faces"));
}

TEST(MeshRepairTest, BookPagesBecomeSheetsOfTheirOwn) {
  const RawMesh raw = testing::BookOfThreeSheets();
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.nonmanifold_edges, 1);
  EXPECT_EQ(r->report.edge_copies, 3);
  EXPECT_EQ(r->report.nonmanifold_vertices, 2);
  EXPECT_EQ(r->report.vertex_copies, 6);
  EXPECT_EQ(r->mesh.num_components(), 3);
  EXPECT_EQ(r->mesh.num_boundary_edges(), 12);  // four a page
  ExpectMapsRecoverInput(raw, *r);
  EXPECT_THAT(RepairMesh(raw, Strict()).status().message(),
              HasSubstr("non-manifold edge (0, 1) is shared by 3 faces"));
}

// The faces of internal face f's sheet: sheet A's faces come first.
bool InSheetA(const RawMesh& raw, int32_t f) {
  return f < static_cast<int32_t>(raw.triangles.size()) / 2;
}

// Two sheets crossing along an edge, four faces in crossing orientations
// (a->b, a->b, b->a, b->a round it): the solid rule pairs a face of one
// sheet with a face of the other, which left the edge joining the same two
// vertices twice; now each sheet keeps its own copy and is whole.
TEST(MeshRepairTest, SheetsCrossingAlongAnEdgeEachKeepTheirOwnCopy) {
  for (bool flip_second : {false, true}) {
    const RawMesh raw = testing::TwoSheetsCrossingAlongAnEdge(3, flip_second);
    absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->report.nonmanifold_edges, 1);
    EXPECT_EQ(r->report.edge_copies, 2);
    EXPECT_EQ(r->report.nonmanifold_vertices, 2);  // a and b
    EXPECT_EQ(r->report.vertex_copies, 4);
    EXPECT_EQ(r->report.reoriented_faces, 0);
    EXPECT_TRUE(r->maps.faces.empty());  // face ids and corners are the input's
    EXPECT_EQ(r->mesh.num_components(), 2);
    // Each sheet is a whole square: its perimeter is the only boundary, and
    // every paired edge joins two faces of one sheet.
    EXPECT_EQ(r->mesh.num_boundary_edges(), 2 * 4 * 6);
    for (int32_t h = 0; h < r->mesh.num_halfedges(); ++h) {
      const int32_t twin = r->mesh.Twin(h);
      if (twin == kNone) continue;
      EXPECT_EQ(InSheetA(raw, Mesh::FaceOf(h)), InSheetA(raw, Mesh::FaceOf(twin))) << h;
    }
    EXPECT_NEAR(r->mesh.TotalArea(), 8, 1e-12);
    ExpectMapsRecoverInput(raw, *r);
    const absl::StatusOr<RepairedMesh> strict = RepairMesh(raw, Strict());
    ASSERT_FALSE(strict.ok());
    EXPECT_THAT(strict.status().message(),
                HasSubstr("non-manifold edge (0, 1) is shared by 4 faces"));
  }
}

// Three sheets of pages and a crossing sheet on one edge: six faces round
// it in every orientation mix; the repair always ends with a valid mesh.
TEST(MeshRepairTest, EdgeOfSixFacesInAnyOrientationIsCut) {
  for (int mask = 0; mask < 64; ++mask) {
    RawMesh raw = testing::BookOfThreeSheets();
    // Three more single faces on the spine, and the pages' faces on it
    // turned as `mask` says.
    for (int k = 0; k < 3; ++k) {
      const double angle = 2 * std::numbers::pi * (k + 0.5) / 3;
      const int32_t p = AddVertex(&raw, Vec3(std::cos(angle), std::sin(angle), 0.5));
      AddTriangle(&raw, {0, 1, p});
    }
    std::vector<int32_t> spine_faces = {1, 3, 5, 6, 7, 8};
    for (int bit = 0; bit < 6; ++bit) {
      if (mask & (1 << bit)) {
        Triangle& t = raw.triangles[spine_faces[bit]];
        std::swap(t[1], t[2]);
      }
    }
    absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
    ASSERT_TRUE(r.ok()) << "mask " << mask << ": " << r.status();
    EXPECT_EQ(r->report.nonmanifold_edges, 1) << mask;
    ExpectMapsRecoverInput(raw, *r);
  }
}

TEST(MeshRepairTest, FlippedFacesOfASphereAreReoriented) {
  const Mesh sphere = gen::Sphere(2, 1.0);
  RawMesh raw = RawOf(sphere, "sphere");
  for (int32_t f : {0, 5, 17, 200}) std::swap(raw.triangles[f][1], raw.triangles[f][2]);
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.reoriented_faces, 4);
  EXPECT_EQ(r->mesh.faces(), sphere.faces());  // the majority's orientation
  ASSERT_EQ(r->maps.faces.size(), raw.triangles.size());
  EXPECT_TRUE(r->maps.faces[5].reoriented);
  EXPECT_FALSE(r->maps.faces[6].reoriented);
  EXPECT_THAT(r->maps.faces[5].corner, ElementsAre(0, 2, 1));
  ExpectMapsRecoverInput(raw, *r);
  const absl::StatusOr<RepairedMesh> strict = RepairMesh(raw, Strict());
  ASSERT_FALSE(strict.ok());
  EXPECT_THAT(strict.status().message(), HasSubstr("in the same direction"));
}

TEST(MeshRepairTest, MobiusStripIsRefused) {
  const absl::StatusOr<RepairedMesh> r = RepairMesh(testing::MobiusStrip());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(r.status().message(), HasSubstr("mobius: the surface is not orientable"));
}

TEST(MeshRepairTest, ZeroAreaFaceIsKept) {
  RawMesh raw = RawOf(gen::Grid(4, 4, 1, 1), "grid");
  const int32_t degenerate = testing::AddZeroAreaFace(&raw, 13);
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.zero_area_faces, 1);
  EXPECT_FALSE(r->report.changed());
  EXPECT_TRUE(r->maps.identity());
  EXPECT_EQ(r->mesh.num_faces(), 34);
  EXPECT_EQ(r->mesh.Area(degenerate), 0);
  EXPECT_EQ(r->mesh.num_boundary_edges(), 16);  // the grid's: the face closes the split
  EXPECT_NEAR(r->mesh.AngleSum(r->mesh.face(degenerate)[2]), 2 * std::numbers::pi, 1e-12);
  const absl::StatusOr<RepairedMesh> strict = RepairMesh(raw, Strict());
  ASSERT_FALSE(strict.ok());
  EXPECT_THAT(strict.status().message(), HasSubstr("has zero area"));
}

TEST(MeshRepairTest, SliversAreCounted) {
  RawMesh raw = RawOf(gen::Grid(4, 4, 1, 1), "grid");
  const int32_t degenerate = testing::AddZeroAreaFace(&raw, 13);
  raw.positions.back() += Vec3(0, 0, 1e-9);  // off the line: a sliver, not zero area
  absl::StatusOr<RepairedMesh> r = RepairMesh(raw);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.zero_area_faces, 0);
  EXPECT_EQ(r->report.sliver_faces, 1);
  EXPECT_GT(r->mesh.Area(degenerate), 0);
}

TEST(MeshRepairTest, WhatCannotBeRepairedIsRefusedWithTheReason) {
  RawMesh nan = RawOf(gen::Grid(2, 2, 1, 1), "nan");
  nan.positions[3].y() = std::nan("");
  EXPECT_THAT(RepairMesh(nan).status().message(),
              HasSubstr("vertex 3 has a non-finite coordinate"));
  RawMesh repeated = RawOf(gen::Grid(2, 2, 1, 1), "repeated");
  repeated.triangles[2] = {4, 1, 4};
  EXPECT_THAT(RepairMesh(repeated).status().message(), HasSubstr("face 2 repeats a vertex"));
  repeated.polygons = true;
  EXPECT_THAT(RepairMesh(repeated).status().message(),
              HasSubstr("face ids count triangles after fan triangulation"));
  RawMesh empty;
  empty.name = "empty";
  EXPECT_THAT(RepairMesh(empty).status().message(), HasSubstr("no faces"));
}

TEST(MeshRepairTest, PolygonWithARepeatedVertexIsRefusedFromAFile) {
  // A quad 0 1 2 1 fans into (0 1 2) and (0 2 1): a duplicate of a face, but
  // a repeated polygon corner is not repairable.
  const absl::StatusOr<RawMesh> raw =
      ParseObjTriangles("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 1 2 3 2\n", "quad.obj");
  ASSERT_TRUE(raw.ok()) << raw.status();
  ASSERT_TRUE(raw->polygons);
  const absl::StatusOr<RepairedMesh> r = RepairMesh(*raw);
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.status().message(), HasSubstr("quad.obj: polygon 1 of the file (4 corners) "
                                              "repeats vertex 1"));
}

TEST(MeshRepairTest, RepairIsDeterministic) {
  const RawMesh raw = testing::TwoCubesSharingAnEdge();
  const absl::StatusOr<RepairedMesh> a = RepairMesh(raw), b = RepairMesh(raw);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->mesh.faces(), b->mesh.faces());
  EXPECT_EQ(a->maps.vertex_copies, b->maps.vertex_copies);
}

// The development meshes, when present: cow_nonmanifold_3k has one
// non-manifold vertex; it is repaired by default and refused when strict.
TEST(MeshRepairTest, CowNonmanifoldIsRepairedOrRefusedWhenStrict) {
  std::string dir;
  if (const char* env = std::getenv("GEODEX_SHARED_MESHES"); env != nullptr && *env != '\0') {
    dir = env;
  } else {
#ifdef GEODEX_SOURCE_DIR
    dir = std::string(GEODEX_SOURCE_DIR) + "/../shared/meshes";
#endif
  }
  const std::string path = dir + "/cow_nonmanifold_3k.obj";
  if (dir.empty() || !std::filesystem::exists(path)) {
    GTEST_SKIP() << "no " << path
                 << " (set GEODEX_SHARED_MESHES, or place the meshes in <source>/../shared/meshes)";
  }
  absl::StatusOr<RepairedMesh> r = LoadAndRepairMesh(path);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->report.nonmanifold_vertices, 1);
  EXPECT_EQ(r->report.vertex_copies, 2);
  EXPECT_EQ(r->report.duplicate_faces + r->report.nonmanifold_edges + r->report.reoriented_faces,
            0);
  EXPECT_EQ(r->mesh.num_vertices(), r->maps.num_input_vertices + 1);
  const absl::StatusOr<RepairedMesh> strict = LoadAndRepairMesh(path, Strict());
  ASSERT_FALSE(strict.ok());
  EXPECT_EQ(strict.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(strict.status().message(), HasSubstr("non-manifold vertex"));
}

}  // namespace
}  // namespace geodex::mesh
