#include "client/cli/outputs.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client::cli {
namespace {

using ::testing::HasSubstr;

std::vector<GeodesicPath> TwoPaths() {
  GeodesicPath p;
  p.points = {{0, {1, 0, 0}}, {1, {0, 1, 0}}, {2, {0, 0, 1}}};
  p.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}};
  p.length = 2;
  GeodesicPath q;
  q.points = {{3, {1, 0, 0}}, {4, {0, 1, 0}}};
  q.positions = {{0, 0, 1}, {0, 0, 2}};
  q.length = 1;
  return {p, q};
}

TEST(PathsToObj, VerticesThenOnePolylinePerPath) {
  const std::string obj = PathsToObj(TwoPaths());
  EXPECT_THAT(obj, HasSubstr("v 1 1 0\n"));
  EXPECT_THAT(obj, HasSubstr("l 1 2 3\n"));
  EXPECT_THAT(obj, HasSubstr("l 4 5\n"));
}

TEST(PathsToPly, HeaderCountsAndEdges) {
  const std::string ply = PathsToPly(TwoPaths());
  EXPECT_THAT(ply, HasSubstr("element vertex 5\n"));
  EXPECT_THAT(ply, HasSubstr("element edge 3\n"));
  EXPECT_THAT(ply, HasSubstr("end_header\n0 0 0 0\n"));
  EXPECT_THAT(ply, HasSubstr("\n0 1\n1 2\n3 4\n"));
}

TEST(PathsToJson, SurfacePointsAndPositions) {
  const std::string json = PathsToJson(TwoPaths());
  EXPECT_THAT(json, HasSubstr("{\"length\": 2, \"points\": [{\"face\": 0, \"w\": [1, 0, 0], "
                              "\"xyz\": [0, 0, 0]}, "));
  EXPECT_EQ(json.front(), '[');
  EXPECT_THAT(json, HasSubstr("]}\n]\n"));
}

TEST(FieldToText, OneLinePerVertex) {
  VertexDistances field;
  field.distances = {0, 1.5, std::numeric_limits<double>::infinity()};
  EXPECT_EQ(FieldToText(field), "0\n1.5\ninf\n");
  field.nearest_source = {0, 1, -1};
  EXPECT_EQ(FieldToText(field), "0 0\n1.5 1\ninf -1\n");
}

TEST(FieldWithinToText, OneLinePerVertexWithinTheRadius) {
  VertexDistancesWithin field;
  field.vertices = {3, 8};
  field.distances = {0.25, 1.5};
  EXPECT_EQ(FieldWithinToText(field), "3 0.25\n8 1.5\n");
  field.nearest_source = {1, 0};
  EXPECT_EQ(FieldWithinToText(field), "3 0.25 1\n8 1.5 0\n");
  EXPECT_EQ(FieldWithinToText({}), "");
  const std::vector<double> dense = DenseDistances(field, 9);
  ASSERT_EQ(dense.size(), 9u);
  EXPECT_EQ(dense[3], 0.25);
  EXPECT_EQ(dense[8], 1.5);
  EXPECT_EQ(dense[0], std::numeric_limits<double>::infinity());
  EXPECT_EQ(DenseDistances(field, 4)[3], 0.25);  // vertex 8 past the end: left out
}

TEST(FieldToPly, ColoredMeshWithQuality) {
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}};
  mesh.faces = {{0, 1, 2}};
  const std::string ply = FieldToPly(mesh, {0, 1, 2, std::numeric_limits<double>::infinity()});
  EXPECT_THAT(ply, HasSubstr("element vertex 4\n"));
  EXPECT_THAT(ply, HasSubstr("property float quality\n"));
  EXPECT_THAT(ply, HasSubstr("element face 1\n"));
  EXPECT_THAT(ply, HasSubstr("\n0 0 0 68 1 84 0\n"));       // nearest: ramp start
  EXPECT_THAT(ply, HasSubstr("\n0 1 0 253 231 37 2\n"));    // farthest: ramp end
  EXPECT_THAT(ply, HasSubstr("\n5 5 5 128 128 128 -1\n"));  // unreachable
  EXPECT_THAT(ply, HasSubstr("\n3 0 1 2\n"));
}

// What FieldToPly wrote, read back line by line the way a PLY reader would.
struct ReadPly {
  int64_t num_vertices = -1, num_faces = -1;
  std::vector<std::string> vertex_properties;
  std::vector<std::vector<double>> vertices;  // x y z red green blue quality
  std::vector<std::vector<int64_t>> faces;    // count, then the ids
  bool ok = false;                            // header and body parsed completely
};

ReadPly ParsePly(const std::string& text) {
  ReadPly ply;
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != "ply") return ply;
  if (!std::getline(in, line) || line != "format ascii 1.0") return ply;
  std::string element;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "element") {
      int64_t count = -1;
      words >> element >> count;
      (element == "vertex" ? ply.num_vertices : ply.num_faces) = count;
    } else if (keyword == "property" && element == "vertex") {
      std::string type, name;
      words >> type >> name;
      ply.vertex_properties.push_back(name);
    }
  }
  if (line != "end_header" || ply.num_vertices < 0 || ply.num_faces < 0) return ply;
  for (int64_t v = 0; v < ply.num_vertices && std::getline(in, line); ++v) {
    std::istringstream words(line);
    std::vector<double> row;
    double x;
    while (words >> x) row.push_back(x);
    ply.vertices.push_back(row);
  }
  for (int64_t f = 0; f < ply.num_faces && std::getline(in, line); ++f) {
    std::istringstream words(line);
    std::vector<int64_t> row;
    int64_t id;
    while (words >> id) row.push_back(id);
    ply.faces.push_back(row);
  }
  ply.ok = static_cast<int64_t>(ply.vertices.size()) == ply.num_vertices &&
           static_cast<int64_t>(ply.faces.size()) == ply.num_faces && !std::getline(in, line);
  return ply;
}

TEST(FieldToPly, ReadsBackAsTheMeshWithDistancesAndColors) {
  // A unit square of two triangles, a vertex on another component (a third
  // triangle) and an unreferenced vertex.
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.125},
                    {5, 5, 5}, {6, 5, 5}, {5, 6, 5}, {-1.0 / 3, 1e-17, 2.5e10}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}};
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> d = {0, 1, std::sqrt(2.0), 1, inf, inf, inf, inf};
  const ReadPly ply = ParsePly(FieldToPly(mesh, d));
  ASSERT_TRUE(ply.ok);
  EXPECT_EQ(ply.num_vertices, 8);
  EXPECT_EQ(ply.num_faces, 3);
  EXPECT_THAT(ply.vertex_properties,
              ::testing::ElementsAre("x", "y", "z", "red", "green", "blue", "quality"));
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const std::vector<double>& row = ply.vertices[v];
    ASSERT_EQ(row.size(), 7u) << v;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(row[c], mesh.positions[v][c]) << v;  // exact
    const std::array<uint8_t, 3> rgb =
        std::isfinite(d[v]) ? RampColor(d[v] / std::sqrt(2.0)) : kUnreachableColor;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(row[3 + c], rgb[c]) << v;
    if (std::isfinite(d[v])) {
      EXPECT_FLOAT_EQ(row[6], d[v]) << v;
    } else {
      EXPECT_EQ(row[6], -1) << v;
    }
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    EXPECT_THAT(ply.faces[f],
                ::testing::ElementsAre(3, mesh.faces[f][0], mesh.faces[f][1], mesh.faces[f][2]));
  }
  // The ramp never gives the unreachable gray.
  for (int i = 0; i <= 1000; ++i) EXPECT_NE(RampColor(i / 1000.0), kUnreachableColor) << i;
}

TEST(FieldToPly, AllAtTheSourceIsTheRampStart) {
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  const ReadPly ply = ParsePly(FieldToPly(mesh, {0, 0, 0}));
  ASSERT_TRUE(ply.ok);
  for (const auto& row : ply.vertices) {
    EXPECT_THAT(row,
                ::testing::ElementsAre(::testing::_, ::testing::_, ::testing::_, 68, 1, 84, 0));
  }
}

TEST(RampColor, MonotoneBrightness) {
  int last = -1;
  for (int i = 0; i <= 10; ++i) {
    const auto c = RampColor(i / 10.0);
    const int brightness = 2 * c[0] + 5 * c[1] + c[2];
    EXPECT_GT(brightness, last) << i;
    last = brightness;
  }
}

TEST(Json, StringsEscapedAndModelsComplete) {
  EXPECT_EQ(JsonString("a\"b\\c\n"), "\"a\\\"b\\\\c\\n\"");
  ModelInfo m;
  m.name = "torus";
  m.state = ModelInfo::State::kServing;
  m.build_report["samples"] = "200";
  const std::string json = ModelToJson(m);
  EXPECT_THAT(json, HasSubstr("\"name\": \"torus\""));
  EXPECT_THAT(json, HasSubstr("\"state\": \"SERVING\""));
  EXPECT_THAT(json, HasSubstr("\"samples\": \"200\""));
  EXPECT_THAT(ModelsTable({m}), HasSubstr("torus"));
}

}  // namespace
}  // namespace geodex::client::cli
