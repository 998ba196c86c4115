#include "client/cli/outputs.h"

#include <limits>

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

TEST(FieldToPly, ColoredMeshWithQuality) {
  MeshGeometry mesh;
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
