// The glTF reader (mesh_io.h) and the GLB writer.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "core/common/file_util.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_formats_testing.h"
#include "core/mesh/mesh_io.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::mesh {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::string TempDir() {
  const auto dir = std::filesystem::temp_directory_path() / "geodex_gltf_test";
  std::filesystem::create_directories(dir);
  return dir.string() + "/";
}

// A glTF file written by hand: one buffer of float32 positions and index
// arrays, its accessors, and the scene's JSON supplied by the test.
class GltfWriter {
 public:
  // Appends float32 VEC3 positions; returns the accessor's index.
  int Positions(const std::vector<Vec3>& positions) {
    const size_t offset = bin_.size();
    for (const Vec3& p : positions) {
      for (int i = 0; i < 3; ++i) Put(static_cast<float>(p[i]));
    }
    return Accessor(offset, positions.size(), 5126, "VEC3");
  }
  // Appends indices of component type 5121 (uint8), 5123 (uint16) or 5125
  // (uint32); returns the accessor's index.
  int Indices(const std::vector<uint32_t>& indices, int component_type) {
    const size_t offset = bin_.size();
    for (uint32_t i : indices) {
      if (component_type == 5121) Put(static_cast<uint8_t>(i));
      if (component_type == 5123) Put(static_cast<uint16_t>(i));
      if (component_type == 5125) Put(i);
    }
    while (bin_.size() % 4 != 0) bin_.push_back('\0');
    return Accessor(offset, indices.size(), component_type, "SCALAR");
  }
  // Replaces the JSON of one accessor (e.g. to make it sparse).
  std::string& accessor_json(int index) { return accessors_[index]; }
  const std::string& bin() const { return bin_; }

  // The whole JSON: `rest` holds "scene", "scenes", "nodes", "meshes"; the
  // buffer's "uri" is `uri` (none in a GLB).
  std::string Json(const std::string& rest, const std::string& uri) const {
    std::vector<std::string> views;
    for (size_t a = 0; a < view_offsets_.size(); ++a) {
      views.push_back(absl::StrFormat(R"({"buffer":0,"byteOffset":%d,"byteLength":%d})",
                                      view_offsets_[a], view_lengths_[a]));
    }
    return absl::StrCat(R"({"asset":{"version":"2.0"},)", rest, R"(,"buffers":[{"byteLength":)",
                        bin_.size(), uri.empty() ? "" : absl::StrCat(R"(,"uri":")", uri, "\""),
                        R"(}],"bufferViews":[)", absl::StrJoin(views, ","), R"(],"accessors":[)",
                        absl::StrJoin(accessors_, ","), "]}");
  }
  // The same as a data: URI .gltf text.
  std::string EmbeddedGltf(const std::string& rest) const {
    std::string base64;
    absl::Base64Escape(bin_, &base64);
    return Json(rest, absl::StrCat("data:application/octet-stream;base64,", base64));
  }
  std::string Glb(const std::string& rest) const {
    std::string json = Json(rest, "");
    json.resize((json.size() + 3) / 4 * 4, ' ');
    std::string bin = bin_;
    bin.resize((bin.size() + 3) / 4 * 4, '\0');
    std::string out;
    auto put32 = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    put32(0x46546C67);
    put32(2);
    put32(static_cast<uint32_t>(28 + json.size() + bin.size()));
    put32(static_cast<uint32_t>(json.size()));
    put32(0x4E4F534A);
    out += json;
    put32(static_cast<uint32_t>(bin.size()));
    put32(0x004E4942);
    out += bin;
    return out;
  }

 private:
  template <typename T>
  void Put(T value) {
    bin_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  int Accessor(size_t offset, size_t count, int component_type, const char* type) {
    view_offsets_.push_back(offset);
    view_lengths_.push_back(bin_.size() - offset);
    accessors_.push_back(absl::StrFormat(R"({"bufferView":%d,"componentType":%d,"count":%d,)"
                                         R"("type":"%s"})",
                                         view_offsets_.size() - 1, component_type, count, type));
    return static_cast<int>(accessors_.size() - 1);
  }

  std::string bin_;
  std::vector<size_t> view_offsets_, view_lengths_;
  std::vector<std::string> accessors_;
};

// A unit square of two triangles in the plane z = 0: positions and indices.
const std::vector<Vec3> kSquare = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
const std::vector<uint32_t> kSquareIndices = {0, 1, 2, 0, 2, 3};

std::string Message(std::string_view contents, const std::string& base_dir = "") {
  absl::StatusOr<RawMesh> raw = ParseGltfTriangles(contents, "bad.gltf", base_dir);
  EXPECT_FALSE(raw.ok());
  EXPECT_EQ(raw.status().code(), absl::StatusCode::kInvalidArgument) << raw.status();
  return std::string(raw.status().message());
}

TEST(GltfTest, GlbReadsBackTheFloat32Mesh) {
  const Mesh torus = gen::Torus(24, 12, std::sqrt(3.0), 0.7);
  absl::StatusOr<RawMesh> raw = ParseGltfTriangles(GlbBytes(torus), "torus.glb", "");
  ASSERT_TRUE(raw.ok()) << raw.status();
  const RawMesh want = testing::FirstCornerOrder(torus, /*round=*/true);
  EXPECT_EQ(raw->triangles, want.triangles);
  EXPECT_EQ(raw->positions, want.positions);
  EXPECT_EQ(raw->weld.welded_corners, 3 * torus.num_faces() - torus.num_vertices());
  for (size_t t = 0; t < raw->input_face.size(); ++t) ASSERT_EQ(raw->input_face[t], t);
}

// Two nodes, one a child with its own transform, and a mesh of two
// primitives (one without indices, one with uint8 indices) used by both:
// faces in the documented order, positions transformed.
TEST(GltfTest, SceneOrderAndNodeTransforms) {
  GltfWriter w;
  const int square = w.Positions(kSquare);
  const int square_indices = w.Indices(kSquareIndices, 5121);
  const int soup = w.Positions({{0, 0, 1}, {1, 0, 1}, {0, 1, 1}});
  const std::string rest =
      R"("scene":0,"scenes":[{"nodes":[1]}],)"
      // Node 1 (the root): translated by (10, 0, 0); its child node 0:
      // rotated a quarter turn about z and scaled by 2.
      R"("nodes":[{"mesh":0,"rotation":[0,0,0.7071067811865476,0.7071067811865476],)"
      R"("scale":[2,2,2]},{"mesh":0,"translation":[10,0,0],"children":[0]}],)"
      R"("meshes":[{"primitives":[)"
      R"({"attributes":{"POSITION":)" +
      std::to_string(soup) + R"(}},)" + R"({"attributes":{"POSITION":)" + std::to_string(square) +
      R"(},"indices":)" + std::to_string(square_indices) + "}]}]";
  for (bool glb : {false, true}) {
    const std::string contents = glb ? w.Glb(rest) : w.EmbeddedGltf(rest);
    absl::StatusOr<RawMesh> raw = ParseGltfTriangles(contents, "scene.gltf", "");
    ASSERT_TRUE(raw.ok()) << raw.status();
    ASSERT_EQ(raw->triangles.size(), 6u);  // (1 + 2) triangles, two nodes
    auto corner = [&](int t, int c) { return raw->positions[raw->triangles[t][c]]; };
    // Node 1 first: the soup triangle, then the square, moved by +10 in x.
    EXPECT_EQ(corner(0, 1), Vec3(11, 0, 1));
    EXPECT_EQ(corner(1, 0), Vec3(10, 0, 0));
    EXPECT_EQ(corner(2, 2), Vec3(10, 1, 0));
    // Its child: (x, y, z) -> 10 + 2 * (-y, x, z).
    EXPECT_NEAR((corner(3, 1) - Vec3(10, 2, 2)).norm(), 0, 1e-12);
    EXPECT_NEAR((corner(4, 1) - Vec3(10, 2, 0)).norm(), 0, 1e-12);
    EXPECT_NEAR((corner(5, 2) - Vec3(8, 0, 0)).norm(), 0, 1e-12);
    // Corners at one place are one vertex, across primitives too: the
    // square's (10, 0, 0) is the child's rotated origin.
    EXPECT_EQ(raw->triangles[1][0], raw->triangles[4][0]);
  }
}

TEST(GltfTest, MatrixTransformAndSceneless) {
  GltfWriter w;
  const int square = w.Positions(kSquare);
  const int indices = w.Indices(kSquareIndices, 5123);
  const std::string mesh = absl::StrFormat(
      R"("meshes":[{"primitives":[{"attributes":{"POSITION":%d},"indices":%d,"mode":4}]}])", square,
      indices);
  // Column-major: x -> x + 5.
  absl::StatusOr<RawMesh> moved =
      ParseGltfTriangles(w.EmbeddedGltf(R"("scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"matrix":)"
                                        R"([1,0,0,0,0,1,0,0,0,0,1,0,5,0,0,1]}],)" +
                                        mesh),
                         "m.gltf", "");
  ASSERT_TRUE(moved.ok()) << moved.status();
  EXPECT_EQ(moved->positions[1], Vec3(6, 0, 0));
  // Without scenes: every mesh once, as stored.
  absl::StatusOr<RawMesh> plain = ParseGltfTriangles(w.EmbeddedGltf(mesh), "plain.gltf", "");
  ASSERT_TRUE(plain.ok()) << plain.status();
  EXPECT_EQ(plain->positions, kSquare);
  EXPECT_EQ(plain->triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
}

TEST(GltfTest, SparsePositionsAreSubstituted) {
  GltfWriter w;
  const int square = w.Positions(kSquare);
  const int indices = w.Indices(kSquareIndices, 5125);
  // Vertex 2 moves to (2, 2, 0): its index (uint8) and value in views of
  // their own.
  const int at = w.Indices({2}, 5121);
  const int value = w.Positions({{2, 2, 0}});
  w.accessor_json(square) = absl::StrFormat(
      R"({"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","sparse":{"count":1,)"
      R"("indices":{"bufferView":%d,"componentType":5121},"values":{"bufferView":%d}}})",
      at, value);
  absl::StatusOr<RawMesh> raw = ParseGltfTriangles(
      w.EmbeddedGltf(absl::StrFormat(
          R"("meshes":[{"primitives":[{"attributes":{"POSITION":%d},"indices":%d}]}])", square,
          indices)),
      "sparse.gltf", "");
  ASSERT_TRUE(raw.ok()) << raw.status();
  EXPECT_EQ(raw->positions[2], Vec3(2, 2, 0));
}

TEST(GltfTest, ExternalBufferIsReadBesideTheFile) {
  GltfWriter w;
  const int square = w.Positions(kSquare);
  const int indices = w.Indices(kSquareIndices, 5125);
  const std::string rest =
      absl::StrFormat(R"("scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
                      R"("meshes":[{"primitives":[{"attributes":{"POSITION":%d},"indices":%d}]}])",
                      square, indices);
  const std::string dir = TempDir();
  ASSERT_TRUE(AtomicWriteFile(dir + "square.gltf", w.Json(rest, "square.bin")).ok());
  ASSERT_TRUE(AtomicWriteFile(dir + "square.bin", w.bin()).ok());
  absl::StatusOr<LoadedMesh> loaded = LoadMeshFile(dir + "square.gltf");
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_EQ(loaded->mesh.num_faces(), 2);
  EXPECT_EQ(loaded->input_face, (std::vector<int32_t>{0, 1}));
  // A short .bin, a missing one, and no file access for in-memory text.
  ASSERT_TRUE(AtomicWriteFile(dir + "square.bin", w.bin().substr(0, 40)).ok());
  EXPECT_THAT(LoadMeshFile(dir + "square.gltf").status().message(),
              AllOf(HasSubstr("square.gltf: not a readable glTF file"), HasSubstr("square.bin")));
  std::filesystem::remove(dir + "square.bin");
  const absl::Status missing = LoadMeshFile(dir + "square.gltf").status();
  EXPECT_EQ(missing.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(missing.message(), AllOf(HasSubstr("square.gltf"), HasSubstr("square.bin")));
  EXPECT_THAT(Message(w.Json(rest, "square.bin")), HasSubstr("square.bin"));
  std::filesystem::remove(dir + "square.gltf");
}

TEST(GltfTest, BadFilesAreRefusedWithTheReason) {
  GltfWriter w;
  const int square = w.Positions(kSquare);
  const int indices = w.Indices(kSquareIndices, 5125);
  auto mesh = [&](const std::string& primitive) {
    return absl::StrCat(R"("scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)",
                        R"("meshes":[{"name":"part","primitives":[)", primitive, "]}]");
  };
  const std::string good =
      absl::StrFormat(R"({"attributes":{"POSITION":%d},"indices":%d})", square, indices);
  const std::string glb = w.Glb(mesh(good));
  ASSERT_TRUE(ParseGltfTriangles(glb, "ok.glb", "").ok());
  // The container.
  EXPECT_THAT(Message(glb.substr(0, glb.size() - 8)), HasSubstr("bad.gltf: GLB: the header says"));
  std::string long_bin = glb;
  const uint32_t too_long = 1000;
  uint32_t json_length;
  std::memcpy(&json_length, glb.data() + 12, 4);
  std::memcpy(long_bin.data() + 20 + json_length, &too_long, 4);
  EXPECT_THAT(Message(long_bin), HasSubstr("GLB: the BIN chunk's 1000 bytes run past the end"));
  EXPECT_THAT(Message("glTF"), HasSubstr("GLB: shorter than its 12-byte header"));
  EXPECT_THAT(Message("{\"asset\":"), HasSubstr("bad.gltf: not a readable glTF file"));
  EXPECT_THAT(Message("{}"), HasSubstr("bad.gltf: not a readable glTF file"));
  // The scene.
  EXPECT_THAT(Message(w.EmbeddedGltf(mesh(absl::StrFormat(
                  R"({"attributes":{"POSITION":%d},"indices":%d,"mode":1})", square, indices)))),
              HasSubstr("bad.gltf: glTF: mesh 0 ('part') primitive 0: a primitive of LINES; "
                        "geodex reads TRIANGLES primitives"));
  EXPECT_THAT(Message(w.EmbeddedGltf(mesh(absl::StrFormat(
                  R"({"attributes":{"POSITION":%d},"indices":%d,"mode":5})", square, indices)))),
              HasSubstr("TRIANGLE_STRIP"));
  EXPECT_THAT(Message(w.EmbeddedGltf(mesh(R"({"attributes":{"NORMAL":0}})"))),
              HasSubstr("primitive 0: no POSITION attribute"));
  const int bad_indices = w.Indices({0, 1, 7}, 5125);
  EXPECT_THAT(Message(w.EmbeddedGltf(mesh(absl::StrFormat(
                  R"({"attributes":{"POSITION":%d},"indices":%d})", square, bad_indices)))),
              HasSubstr("index 2 of triangle 0 is 7, out of range [0, 4)"));
  const int two = w.Indices({0, 1}, 5125);
  EXPECT_THAT(Message(w.EmbeddedGltf(mesh(
                  absl::StrFormat(R"({"attributes":{"POSITION":%d},"indices":%d})", square, two)))),
              HasSubstr("2 indices, not a multiple of 3"));
  const int nan = w.Positions({{0, 0, 0}, {1, 0, 0}, {0, std::nan(""), 0}});
  EXPECT_THAT(
      Message(w.EmbeddedGltf(mesh(absl::StrFormat(R"({"attributes":{"POSITION":%d}})", nan)))),
      HasSubstr("has a non-finite position"));
  EXPECT_THAT(
      Message(w.EmbeddedGltf(mesh(absl::StrFormat(R"({"attributes":{"POSITION":%d}})", indices)))),
      HasSubstr("type"));
  // An accessor past its view.
  w.accessor_json(square) = R"({"bufferView":0,"componentType":5126,"count":5,"type":"VEC3"})";
  EXPECT_THAT(Message(w.EmbeddedGltf(mesh(good))), HasSubstr("run past the end of bufferView 0"));
  w.accessor_json(square) = R"({"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"})";
  // A node that is its own descendant.
  EXPECT_THAT(Message(w.EmbeddedGltf(absl::StrCat(
                  R"("scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"children":[1]},)",
                  R"({"children":[0]}],"meshes":[{"primitives":[)", good, "]}]"))),
              HasSubstr("node 0 is reached twice"));
  EXPECT_THAT(Message(w.EmbeddedGltf(
                  absl::StrCat(R"("extensionsRequired":["KHR_draco_mesh_compression"],)",
                               R"("extensionsUsed":["KHR_draco_mesh_compression"],)", mesh(good)))),
              HasSubstr("requires KHR_draco_mesh_compression"));
  EXPECT_THAT(Message(w.EmbeddedGltf(R"("scenes":[{"nodes":[]}])")),
              HasSubstr("the default scene has no triangles"));
}

}  // namespace
}  // namespace geodex::mesh
