// The STL reader and writer (mesh_io.h) and corner welding (ReadOptions).

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/file_util.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_formats_testing.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_repair.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::mesh {
namespace {

using ::testing::AllOf;
using testing::FirstCornerOrder;
using ::testing::HasSubstr;

std::string TempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("geodex_stl_test_" + name)).string();
}

void ExpectSameTriangles(const RawMesh& got, const RawMesh& want) {
  EXPECT_EQ(got.triangles, want.triangles);
  ASSERT_EQ(got.positions.size(), want.positions.size());
  for (size_t v = 0; v < got.positions.size(); ++v) {
    ASSERT_EQ(got.positions[v], want.positions[v]) << "vertex " << v;
  }
  for (size_t t = 0; t < got.input_face.size(); ++t) ASSERT_EQ(got.input_face[t], t);
}

// A torus whose positions are not float32 numbers (a rotation and an
// irrational scale), so that rounding shows.
Mesh Torus() {
  const Mesh t = gen::Torus(24, 12, 2.0, 0.7);
  std::vector<Vec3> positions;
  for (const Vec3& p : t.positions()) positions.push_back(std::sqrt(2.0) * p + Vec3(0.1, 0, 0));
  return *Mesh::Create(positions, t.faces(), "torus");
}

TEST(StlTest, BinaryReadsBackTheFloat32Mesh) {
  const Mesh torus = Torus();
  const std::string bytes = StlBytes(torus, /*binary=*/true);
  EXPECT_EQ(bytes.size(), 84 + 50 * static_cast<size_t>(torus.num_faces()));
  absl::StatusOr<RawMesh> raw = ParseStlTriangles(bytes, "torus.stl");
  ASSERT_TRUE(raw.ok()) << raw.status();
  ExpectSameTriangles(*raw, FirstCornerOrder(torus, /*round=*/true));
  EXPECT_TRUE(raw->weld.welded);
  EXPECT_EQ(raw->weld.welded_corners, 3 * torus.num_faces() - torus.num_vertices());
  EXPECT_EQ(raw->weld.degenerate_corners, 0);
  EXPECT_NE(raw->positions[0], torus.position(0));  // rounded
}

TEST(StlTest, AsciiReadsBackTheSameDoubles) {
  const Mesh torus = Torus();
  absl::StatusOr<RawMesh> raw = ParseStlTriangles(StlBytes(torus, /*binary=*/false), "t.stl");
  ASSERT_TRUE(raw.ok()) << raw.status();
  ExpectSameTriangles(*raw, FirstCornerOrder(torus, /*round=*/false));
}

TEST(StlTest, WeldedStlIsTheSameMeshAsTheObjOfItsPositions) {
  const Mesh sphere = gen::Sphere(3, 1.0);
  const std::string stl = TempPath("sphere.stl");
  ASSERT_TRUE(WriteStl(sphere, stl, /*binary=*/true).ok());
  absl::StatusOr<LoadedMesh> loaded = LoadMeshFile(stl);
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  const RawMesh want = FirstCornerOrder(sphere, /*round=*/true);
  EXPECT_EQ(loaded->mesh.faces(), want.triangles);
  EXPECT_EQ(loaded->mesh.positions(), want.positions);
  EXPECT_EQ(loaded->mesh.num_boundary_edges(), 0);
  // The build report names the welding.
  absl::StatusOr<RepairedMesh> repaired = LoadAndRepairMesh(stl);
  ASSERT_TRUE(repaired.ok()) << repaired.status();
  EXPECT_FALSE(repaired->report.changed());
  EXPECT_THAT(repaired->report.ToText(),
              AllOf(HasSubstr(absl::StrCat("mesh_welded_corners = ",
                                           3 * sphere.num_faces() - sphere.num_vertices(), "\n")),
                    HasSubstr("mesh_weld_tolerance = 0\n"),
                    HasSubstr("mesh_degenerate_corners_unwelded = 0\n")));
  EXPECT_THAT(repaired->report.Summary(),
              HasSubstr(absl::StrCat("; ", 3 * sphere.num_faces() - sphere.num_vertices(),
                                     " corners welded")));
  std::filesystem::remove(stl);
}

TEST(StlTest, AsciiVariantsAreRead) {
  // Keywords in any case, a name with spaces, a facet without a normal,
  // two solids, numbers in every format.
  const std::string text =
      "  SOLID my part, v2\n"
      "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n"
      " endloop\nendfacet\n"
      "ENDSOLID my part, v2\n"
      "solid\n"
      "facet outer loop vertex 1 0 0 vertex +1e0 1.0 0 vertex 0 1 -0 endloop endfacet\n"
      "endsolid\n";
  absl::StatusOr<RawMesh> raw = ParseStlTriangles(text, "variants.stl");
  ASSERT_TRUE(raw.ok()) << raw.status();
  ASSERT_EQ(raw->triangles.size(), 2u);
  EXPECT_EQ(raw->positions.size(), 4u);  // -0 and 0 are one position
  EXPECT_EQ(raw->triangles[1], (Triangle{1, 3, 2}));
}

TEST(StlTest, BinaryWhoseHeaderSaysSolidIsBinary) {
  std::string bytes = StlBytes(gen::Sphere(1, 1.0), /*binary=*/true);
  std::memcpy(bytes.data(), "solid exported by a CAD tool", 28);
  absl::StatusOr<RawMesh> raw = ParseStlTriangles(bytes, "cad.stl");
  ASSERT_TRUE(raw.ok()) << raw.status();
  EXPECT_EQ(raw->triangles.size(), 80u);
}

TEST(StlTest, BadFilesAreRefusedNamingFileAndPlace) {
  const std::string binary = StlBytes(gen::Sphere(1, 1.0), /*binary=*/true);
  const std::string ascii = StlBytes(gen::Sphere(1, 1.0), /*binary=*/false);
  auto message = [](std::string_view contents) {
    absl::StatusOr<RawMesh> raw = ParseStlTriangles(contents, "bad.stl");
    EXPECT_FALSE(raw.ok());
    EXPECT_EQ(raw.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(raw.status().message());
  };
  EXPECT_THAT(message(binary.substr(0, binary.size() - 1)),
              AllOf(HasSubstr("bad.stl: binary STL: the header counts 80 triangles (4084 bytes) "
                              "but the file has 4083 bytes"),
                    HasSubstr("truncated")));
  std::string wrong_count = binary;
  wrong_count[80] = 79;
  EXPECT_THAT(message(wrong_count), HasSubstr("counts 79 triangles (4034 bytes) but the file "
                                              "has 4084 bytes (a wrong count"));
  std::string nan = binary;
  const float not_a_number = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan.data() + 84 + 50 * 7 + 12 + 12 + 4, &not_a_number, 4);
  EXPECT_THAT(message(nan), HasSubstr("triangle 7 corner 1 has a non-finite coordinate"));
  std::string empty = binary.substr(0, 84);
  empty[80] = 0;
  EXPECT_THAT(message(empty), HasSubstr("bad.stl: the file has no triangles"));
  EXPECT_THAT(message("abc"), HasSubstr("not an STL file"));
  EXPECT_THAT(message(""), HasSubstr("not an STL file"));
  // ASCII: truncated anywhere, NaN, polygons, garbage.
  const size_t cut = ascii.find("vertex ", ascii.size() / 2) + 7;
  EXPECT_THAT(message(ascii.substr(0, cut)), HasSubstr("file ends inside a facet (truncated?)"));
  EXPECT_THAT(message(ascii.substr(0, ascii.size() - 16)),
              HasSubstr("file ends before 'endsolid' (truncated?)"));
  EXPECT_THAT(message("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\n"),
              HasSubstr("bad.stl: line 4: coordinate 'nan' is not finite"));
  EXPECT_THAT(message("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                      "vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n"),
              HasSubstr("line 8: facet 0 has 4 vertices (STL facets are triangles)"));
  EXPECT_THAT(message("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 zero 0\n"),
              HasSubstr("line 4: coordinate 'zero' is not a number"));
  EXPECT_THAT(message("solid x\nendsolid x\n"), HasSubstr("no triangles"));
  EXPECT_THAT(message("solid x\nfacet normal 0 0 1\ninner loop\n"),
              HasSubstr("line 3: facet 0: expected 'outer loop', found 'inner'"));
}

TEST(StlTest, TriangleWithCoincidentCornersKeepsThreeVertices) {
  // A triangle of zero area with two equal corners: the second keeps a
  // vertex of its own, so the triangle has three (a zero-length edge).
  const std::string text =
      "solid s\n"
      "facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 endloop endfacet\n"
      "facet normal 0 0 1 outer loop vertex 1 0 0 vertex 1 0 0 vertex 0 1 0 endloop endfacet\n"
      "endsolid s\n";
  absl::StatusOr<RawMesh> raw = ParseStlTriangles(text, "degenerate.stl");
  ASSERT_TRUE(raw.ok()) << raw.status();
  EXPECT_EQ(raw->triangles[1], (Triangle{1, 3, 2}));
  EXPECT_EQ(raw->positions[3], raw->positions[1]);
  EXPECT_EQ(raw->weld.degenerate_corners, 1);
  EXPECT_EQ(raw->weld.welded_corners, 2);
  absl::StatusOr<RepairedMesh> repaired = RepairMesh(*raw);
  ASSERT_TRUE(repaired.ok()) << repaired.status();
  EXPECT_EQ(repaired->report.zero_area_faces, 1);
}

// A grid whose corners are each moved by a different tiny amount, as float
// rounding in a converter does: exact welding leaves a soup, a tolerance
// welds it back.
TEST(StlTest, WeldToleranceJoinsNearbyCorners) {
  const Mesh grid = gen::Grid(6, 6, 1.0, 1.0);
  std::vector<Vec3> corners;
  int k = 0;
  for (const Triangle& t : grid.faces()) {
    for (int32_t v : t) {
      corners.push_back(grid.position(v) + 1e-9 * Vec3(k % 7, k % 5, k % 3));
      ++k;
    }
  }
  std::string text = "solid jittered\n";
  for (size_t c = 0; c < corners.size(); c += 3) {
    text += "facet normal 0 0 1 outer loop\n";
    for (int i = 0; i < 3; ++i) {
      absl::StrAppendFormat(&text, "vertex %.17g %.17g %.17g\n", corners[c + i].x(),
                            corners[c + i].y(), corners[c + i].z());
    }
    text += "endloop endfacet\n";
  }
  text += "endsolid jittered\n";
  absl::StatusOr<RawMesh> exact = ParseStlTriangles(text, "jittered.stl");
  ASSERT_TRUE(exact.ok()) << exact.status();
  EXPECT_GT(exact->positions.size(), 2u * grid.num_vertices());  // mostly separate triangles
  ReadOptions options;
  options.weld_tolerance = 1e-6;
  absl::StatusOr<RawMesh> welded = ParseStlTriangles(text, "jittered.stl", options);
  ASSERT_TRUE(welded.ok()) << welded.status();
  EXPECT_EQ(welded->positions.size(), static_cast<size_t>(grid.num_vertices()));
  EXPECT_EQ(welded->weld.welded_corners, 3 * grid.num_faces() - grid.num_vertices());
  EXPECT_EQ(welded->weld.tolerance, 1e-6);
  // Every corner moved by at most the tolerance (the diagonal is sqrt(2)).
  for (size_t c = 0; c < corners.size(); ++c) {
    const Vec3& at = welded->positions[welded->triangles[c / 3][c % 3]];
    EXPECT_LE((at - corners[c]).norm(), 1e-6 * std::sqrt(2.0)) << c;
  }
  absl::StatusOr<LoadedMesh> mesh = CreateLoadedMesh(*welded);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_EQ(mesh->mesh.num_boundary_edges(), grid.num_boundary_edges());
}

TEST(StlTest, WeldToleranceIsCheckedAndOnlyForCornerFormats) {
  EXPECT_TRUE(ValidateWeldTolerance(0).ok());
  EXPECT_TRUE(ValidateWeldTolerance(1e-6).ok());
  for (double bad : {-1e-6, 1e-13, 2.0, std::nan("")}) {
    EXPECT_EQ(ValidateWeldTolerance(bad).code(), absl::StatusCode::kInvalidArgument) << bad;
  }
  const std::string obj = TempPath("tri.obj");
  ASSERT_TRUE(AtomicWriteFile(obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").ok());
  ReadOptions options;
  options.weld_tolerance = 1e-6;
  const absl::StatusOr<Mesh> loaded = LoadMesh(obj, options);
  EXPECT_EQ(loaded.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(loaded.status().message(),
              HasSubstr("a weld tolerance applies to STL and glTF files"));
  EXPECT_TRUE(LoadMesh(obj).ok());
  std::filesystem::remove(obj);
}

}  // namespace
}  // namespace geodex::mesh
