#include "client/cli/decal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "client/cli/decal_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tiny_obj_loader.h"

namespace geodex::client::cli {
namespace {

using decal_testing::FlatGrid;
using decal_testing::PlanarExpMap;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

// What an OBJ reader takes from DecalToObj's file.
struct ReadObj {
  std::vector<Position> v;
  std::vector<std::array<double, 2>> vt;
  std::vector<std::array<int64_t, 6>> f;           // v/vt of each corner, 1-based
  std::vector<int64_t> mesh_vertices, mesh_faces;  // from the id comments
  std::vector<std::string> id_comment_lines;
  std::string mtllib, usemtl;
  bool ok = true;
};

// Expands "a b-c ..." into the ids.
bool AppendIds(const std::string& ranges, std::vector<int64_t>* ids) {
  for (const absl::string_view run : absl::StrSplit(ranges, ' ', absl::SkipEmpty())) {
    const std::vector<std::string> ends = absl::StrSplit(run, '-');
    int64_t first = 0, last = 0;
    if (ends.size() > 2 || !absl::SimpleAtoi(ends[0], &first) ||
        !absl::SimpleAtoi(ends.back(), &last) || last < first) {
      return false;
    }
    for (int64_t id = first; id <= last; ++id) ids->push_back(id);
  }
  return true;
}

ReadObj ParseObj(const std::string& text) {
  ReadObj obj;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    for (const char* prefix : {"# mesh vertices:", "# mesh faces:"}) {
      if (line.rfind(prefix, 0) == 0) {
        obj.id_comment_lines.push_back(line);
        const bool vertices = std::string(prefix) == "# mesh vertices:";
        obj.ok &= AppendIds(line.substr(std::string(prefix).size()),
                            vertices ? &obj.mesh_vertices : &obj.mesh_faces);
      }
    }
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "v") {
      Position p;
      obj.ok &= static_cast<bool>(words >> p[0] >> p[1] >> p[2]);
      obj.v.push_back(p);
    } else if (keyword == "vt") {
      std::array<double, 2> t;
      obj.ok &= static_cast<bool>(words >> t[0] >> t[1]);
      obj.vt.push_back(t);
    } else if (keyword == "f") {
      std::array<int64_t, 6> corners;
      char slash1, slash2, slash3;
      obj.ok &= static_cast<bool>(words >> corners[0] >> slash1 >> corners[1] >> corners[2] >>
                                  slash2 >> corners[3] >> corners[4] >> slash3 >> corners[5]);
      obj.ok &= slash1 == '/' && slash2 == '/' && slash3 == '/';
      std::string rest;
      obj.ok &= !(words >> rest);  // triangles only
      obj.f.push_back(corners);
    } else if (keyword == "mtllib") {
      words >> obj.mtllib;
    } else if (keyword == "usemtl") {
      words >> obj.usemtl;
    }
  }
  return obj;
}

// The faces of `mesh` whose three vertices are in `map`, found directly.
std::vector<int64_t> CoveredFaces(const Mesh& mesh, const ExpMap& map) {
  const std::set<int32_t> in_map(map.vertices.begin(), map.vertices.end());
  std::vector<int64_t> faces;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (std::all_of(mesh.faces[f].begin(), mesh.faces[f].end(),
                    [&](uint32_t vertex) { return in_map.count(static_cast<int32_t>(vertex)); })) {
      faces.push_back(static_cast<int64_t>(f));
    }
  }
  return faces;
}

// Every OBJ face is its mesh face, same corners in the same order, and
// every OBJ vertex has the texture coordinates of its map entry.
void ExpectObjIsThePatch(const ReadObj& obj, const Mesh& mesh, const ExpMap& map, double radius) {
  ASSERT_TRUE(obj.ok);
  ASSERT_EQ(obj.mesh_vertices.size(), obj.v.size());
  ASSERT_EQ(obj.vt.size(), obj.v.size());
  ASSERT_EQ(obj.mesh_faces.size(), obj.f.size());
  EXPECT_EQ(obj.mesh_faces, CoveredFaces(mesh, map));
  EXPECT_TRUE(std::is_sorted(obj.mesh_vertices.begin(), obj.mesh_vertices.end()));
  std::set<int64_t> used;
  for (size_t k = 0; k < obj.f.size(); ++k) {
    const auto& mesh_face = mesh.faces[obj.mesh_faces[k]];
    for (int c = 0; c < 3; ++c) {
      const int64_t index = obj.f[k][2 * c];
      EXPECT_EQ(obj.f[k][2 * c + 1], index) << "face " << k;
      ASSERT_GE(index, 1);
      ASSERT_LE(index, static_cast<int64_t>(obj.v.size()));
      EXPECT_EQ(obj.mesh_vertices[index - 1], mesh_face[c]) << "face " << k << " corner " << c;
      EXPECT_EQ(obj.v[index - 1], mesh.positions[mesh_face[c]]);  // %.17g: exact
      used.insert(index);
    }
  }
  EXPECT_EQ(used.size(), obj.v.size()) << "an OBJ vertex no face uses";
  for (size_t k = 0; k < obj.v.size(); ++k) {
    const auto entry = std::lower_bound(map.vertices.begin(), map.vertices.end(),
                                        static_cast<int32_t>(obj.mesh_vertices[k]));
    ASSERT_NE(entry, map.vertices.end());
    const size_t i = entry - map.vertices.begin();
    EXPECT_NEAR(obj.vt[k][0], map.u[i] / (2 * radius) + 0.5, 1e-8) << k;
    EXPECT_NEAR(obj.vt[k][1], map.v[i] / (2 * radius) + 0.5, 1e-8) << k;
  }
}

TEST(DecalToObj, PatchCountsRenumberingAndTextureCoordinates) {
  // Spacing 0.5; radius 1 takes the 3 x 3 block round the centre and the
  // four axis vertices at distance 1, each of which completes one face with
  // the block. Mesh vertex 0, added by hand, completes none.
  const Mesh mesh = FlatGrid(4);
  ExpMap map = PlanarExpMap(mesh, 0, 0, 1.0);
  ASSERT_EQ(map.vertices.size(), 13u);
  map.vertices.insert(map.vertices.begin(), 0);
  map.r.insert(map.r.begin(), std::sqrt(2.0));
  map.theta.insert(map.theta.begin(), -0.75 * std::numbers::pi);
  map.u.insert(map.u.begin(), -1.0);
  map.v.insert(map.v.begin(), -1.0);
  const absl::StatusOr<DecalFiles> files = DecalToObj(mesh, map, 1.0, "decal.mtl", "decal.png");
  ASSERT_TRUE(files.ok()) << files.status();
  const ReadObj obj = ParseObj(files->obj);
  EXPECT_EQ(obj.v.size(), 13u);
  EXPECT_EQ(obj.vt.size(), 13u);
  EXPECT_EQ(obj.f.size(), 12u);
  EXPECT_THAT(obj.id_comment_lines, ElementsAre("# mesh vertices: 2 6-8 10-14 16-18 22",
                                                "# mesh faces: 5 10-13 15-16 18-21 26"));
  ExpectObjIsThePatch(obj, mesh, map, 1.0);
  // The centre, mesh vertex 12, is OBJ vertex 7 at the texture's centre; the
  // corner (0.5, 0.5), vertex 18, is OBJ vertex 12.
  EXPECT_EQ(obj.vt[6], (std::array<double, 2>{0.5, 0.5}));
  EXPECT_EQ(obj.vt[11], (std::array<double, 2>{0.75, 0.75}));
  // Face 5 = (2, 8, 7), then cell (1, 1) = (6, 7, 12), (6, 12, 11).
  EXPECT_THAT(files->obj, HasSubstr("\nf 1/1 4/4 3/3\nf 2/2 3/3 7/7\nf 2/2 7/7 6/6\n"));

  EXPECT_EQ(obj.mtllib, "decal.mtl");
  EXPECT_EQ(obj.usemtl, "geodex_decal");
  EXPECT_THAT(files->mtl, HasSubstr("newmtl geodex_decal\n"));
  EXPECT_THAT(files->mtl, HasSubstr("\nmap_Kd decal.png\n"));
  for (const char* key : {"\nKa ", "\nKd ", "\nKs ", "\nillum 1\n"}) {
    EXPECT_THAT(files->mtl, HasSubstr(key));
  }
  // The mtllib line comes before the first usemtl, as readers expect.
  EXPECT_LT(files->obj.find("mtllib "), files->obj.find("usemtl "));
}

// An independent reader (tinyobjloader, as MeshLab-style importers read OBJ)
// finds the material, its texture and a texture coordinate for every corner.
TEST(DecalToObj, AnIndependentReaderFindsTheTexturedPatch) {
  const Mesh mesh = FlatGrid(6);
  const ExpMap map = PlanarExpMap(mesh, 0, 0, 1.2);
  const absl::StatusOr<DecalFiles> files = DecalToObj(mesh, map, 1.2, "d.mtl", "d_checker.png");
  ASSERT_TRUE(files.ok()) << files.status();
  const std::string dir = ::testing::TempDir();
  for (const auto& [name, text] :
       {std::pair{"d.obj", files->obj}, std::pair{"d.mtl", files->mtl}}) {
    std::ofstream(dir + "/" + name) << text;
  }
  tinyobj::ObjReaderConfig config;
  config.mtl_search_path = dir;
  config.triangulate = false;
  tinyobj::ObjReader reader;
  ASSERT_TRUE(reader.ParseFromFile(dir + "/d.obj", config)) << reader.Error();
  EXPECT_EQ(reader.Warning(), "");
  ASSERT_EQ(reader.GetMaterials().size(), 1u);
  EXPECT_EQ(reader.GetMaterials()[0].diffuse_texname, "d_checker.png");
  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  EXPECT_EQ(attrib.texcoords.size() / 2, attrib.vertices.size() / 3);
  size_t corners = 0;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    for (const tinyobj::index_t& index : shape.mesh.indices) {
      ++corners;
      EXPECT_GE(index.texcoord_index, 0);
    }
    for (const int material : shape.mesh.material_ids) EXPECT_EQ(material, 0);
  }
  EXPECT_GT(corners, 30u);
  EXPECT_EQ(corners, 3 * ParseObj(files->obj).f.size());
}

TEST(DecalToObj, FacesWithAVertexOutsideTheMapAreLeftOut) {
  const Mesh mesh = FlatGrid(4);
  ExpMap map = PlanarExpMap(mesh, 0, 0, 0.8);  // the 3 x 3 block, 6..18
  const auto corner = std::find(map.vertices.begin(), map.vertices.end(), 18);
  ASSERT_NE(corner, map.vertices.end());
  const size_t i = corner - map.vertices.begin();
  for (auto* column : {&map.r, &map.theta, &map.u, &map.v}) column->erase(column->begin() + i);
  map.vertices.erase(corner);

  const absl::StatusOr<DecalFiles> files = DecalToObj(mesh, map, 0.8, "a.mtl", "a.png");
  ASSERT_TRUE(files.ok()) << files.status();
  const ReadObj obj = ParseObj(files->obj);
  EXPECT_EQ(obj.f.size(), 6u);  // cell (2, 2), faces 20 and 21, had vertex 18
  EXPECT_EQ(obj.v.size(), 8u);
  EXPECT_THAT(obj.id_comment_lines,
              ElementsAre("# mesh vertices: 6-8 11-13 16-17", "# mesh faces: 10-13 18-19"));
  ExpectObjIsThePatch(obj, mesh, map, 0.8);
}

TEST(DecalToObj, LargePatchIdCommentsStayShortAndComplete) {
  const Mesh mesh = FlatGrid(60);
  const ExpMap map = PlanarExpMap(mesh, 0.013, -0.021, 0.9);
  const absl::StatusOr<DecalFiles> files = DecalToObj(mesh, map, 0.9, "big.mtl", "big.png");
  ASSERT_TRUE(files.ok()) << files.status();
  const ReadObj obj = ParseObj(files->obj);
  ExpectObjIsThePatch(obj, mesh, map, 0.9);
  EXPECT_GT(obj.f.size(), 1000u);
  EXPECT_GT(obj.id_comment_lines.size(), 4u);
  for (const std::string& line : obj.id_comment_lines) EXPECT_LE(line.size(), 100u) << line;
  // The texture's disc: every vt within the unit square.
  for (const auto& [s, t] : obj.vt) {
    EXPECT_GE(s, 0);
    EXPECT_LE(s, 1);
    EXPECT_GE(t, 0);
    EXPECT_LE(t, 1);
  }
}

TEST(DecalToObj, BadInputIsAnError) {
  const Mesh mesh = FlatGrid(4);
  const ExpMap good = PlanarExpMap(mesh, 0, 0, 0.8);
  const auto code = [&](const ExpMap& map, double radius = 0.8, const Mesh* m = nullptr,
                        const std::string& mtl = "d.mtl", const std::string& png = "d.png") {
    return DecalToObj(m ? *m : mesh, map, radius, mtl, png).status().code();
  };
  ASSERT_EQ(code(good), absl::StatusCode::kOk);

  ExpMap map = good;
  map.u.pop_back();
  EXPECT_EQ(code(map), absl::StatusCode::kInvalidArgument) << "sizes disagree";
  map = good;
  map.theta.push_back(0);
  EXPECT_EQ(code(map), absl::StatusCode::kInvalidArgument) << "sizes disagree";
  map = good;
  map.vertices.back() = 25;
  EXPECT_EQ(code(map), absl::StatusCode::kOutOfRange) << "vertex past the end";
  map = good;
  map.vertices.front() = -1;
  EXPECT_EQ(code(map), absl::StatusCode::kInvalidArgument) << "negative vertex";
  map = good;
  std::swap(map.vertices[0], map.vertices[1]);
  EXPECT_EQ(code(map), absl::StatusCode::kInvalidArgument) << "not ascending";
  map = good;
  map.vertices[1] = map.vertices[0];
  EXPECT_EQ(code(map), absl::StatusCode::kInvalidArgument) << "repeated";
  map = good;
  map.v[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(code(map), absl::StatusCode::kInvalidArgument) << "NaN";
  map = good;
  map.r[2] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(code(map), absl::StatusCode::kInvalidArgument) << "infinite r";
  EXPECT_EQ(code(ExpMap{}), absl::StatusCode::kInvalidArgument) << "empty";
  EXPECT_EQ(code(PlanarExpMap(mesh, 0, 0, 0.4)), absl::StatusCode::kInvalidArgument)
      << "no complete face";  // the centre alone
  for (const double radius : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                              std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(code(good, radius), absl::StatusCode::kInvalidArgument) << radius;
  }
  for (const char* name : {"", "my decal.mtl", "a#b.mtl", "tab\t.mtl", "line\n.mtl"}) {
    EXPECT_EQ(code(good, 0.8, nullptr, name), absl::StatusCode::kInvalidArgument) << name;
    EXPECT_EQ(code(good, 0.8, nullptr, "d.mtl", name), absl::StatusCode::kInvalidArgument) << name;
  }
  map = good;
  map.version = 3;
  Mesh other_version = mesh;
  other_version.version = 4;
  EXPECT_EQ(code(map, 0.8, &other_version), absl::StatusCode::kFailedPrecondition);
  other_version.version = 3;
  EXPECT_EQ(code(map, 0.8, &other_version), absl::StatusCode::kOk);
  Mesh bad_face = mesh;
  bad_face.faces.push_back({0, 1, 99});
  EXPECT_EQ(code(good, 0.8, &bad_face), absl::StatusCode::kOutOfRange);
  Mesh nan_position = mesh;
  nan_position.positions[12][2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(code(good, 0.8, &nan_position), absl::StatusCode::kInvalidArgument);
}

TEST(DecalPatch, FacesWithAllThreeVerticesInTheMap) {
  const Mesh mesh = FlatGrid(4);
  const ExpMap map = PlanarExpMap(mesh, 0, 0, 0.8);
  const absl::StatusOr<DecalPatch> patch = FindDecalPatch(mesh, map);
  ASSERT_TRUE(patch.ok()) << patch.status();
  EXPECT_THAT(patch->faces, ElementsAre(10, 11, 12, 13, 18, 19, 20, 21));
  ASSERT_EQ(patch->map_entry.size(), mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const auto it = std::find(map.vertices.begin(), map.vertices.end(), static_cast<int32_t>(v));
    EXPECT_EQ(patch->map_entry[v], it == map.vertices.end() ? -1 : it - map.vertices.begin());
  }
}

TEST(DecalTextureCoordinates, TheDiscOfTheRadiusFillsTheUnitSquare) {
  using St = std::array<double, 2>;
  EXPECT_EQ(DecalTextureCoordinates(0, 0, 2), (St{0.5, 0.5}));
  EXPECT_EQ(DecalTextureCoordinates(2, 0, 2), (St{1, 0.5}));
  EXPECT_EQ(DecalTextureCoordinates(0, -2, 2), (St{0.5, 0}));
  EXPECT_EQ(DecalTextureCoordinates(-1, 1, 2), (St{0.25, 0.75}));
}

}  // namespace
}  // namespace geodex::client::cli
