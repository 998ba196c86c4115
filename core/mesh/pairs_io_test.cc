#include "core/mesh/pairs_io.h"

#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::mesh {
namespace {

using ::testing::HasSubstr;

TEST(ParsePairsTest, FacePointsAndVertexIds) {
  absl::StatusOr<std::vector<PointPair>> pairs = ParsePairs(
      "# a comment\n"
      "0 1 0 0 5 0.2 0.3 0.5\n"
      "v 17 v 42\n"
      "\n"
      "v 3, 5 0.2 0.3 0.5\n"
      "5 0.2 0.3 0.5 v 0\n");
  ASSERT_TRUE(pairs.ok()) << pairs.status();
  ASSERT_EQ(pairs->size(), 4u);
  EXPECT_EQ((*pairs)[0].b.face, 5);
  EXPECT_EQ((*pairs)[0].vertex, (std::array<int32_t, 2>{kNone, kNone}));
  EXPECT_EQ((*pairs)[1].vertex, (std::array<int32_t, 2>{17, 42}));
  EXPECT_EQ((*pairs)[1].line, 3);
  EXPECT_EQ((*pairs)[2].vertex, (std::array<int32_t, 2>{3, kNone}));
  EXPECT_EQ((*pairs)[2].b.w, (std::array<double, 3>{0.2, 0.3, 0.5}));
  EXPECT_EQ((*pairs)[3].vertex, (std::array<int32_t, 2>{kNone, 0}));
}

TEST(ParsePairsTest, ErrorsNameTheLineAndTheField) {
  EXPECT_EQ(ParsePairs("0 1 0 0 5 0 0\n").status().message(),
            "line 1: expected 8 fields 'fa a0 a1 a2 fb b0 b1 b2', found 7");
  EXPECT_EQ(ParsePairs("v 1 v\n").status().message(),
            "line 1: expected 4 fields ('fa a0 a1 a2 fb b0 b1 b2', a point 'v ID' for a vertex), "
            "found 3");
  EXPECT_EQ(ParsePairs("v -1 v 2\n").status().message(),
            "line 1: field 2 ('-1') is not a vertex id");
  EXPECT_EQ(ParsePairs("0 1 0 0 v x\n").status().message(),
            "line 1: field 6 ('x') is not a vertex id");
  EXPECT_EQ(ParsePairs("0 1 nan 0 v 1\n").status().message(),
            "line 1: field 3 ('nan') is not a finite number");
}

TEST(ParsePairsTest, VerticesResolveToTheirLowestFace) {
  const Mesh sphere = gen::Sphere(1, 1.0);
  const std::vector<SurfacePoint> lowest = LowestFacePoints(sphere);
  ASSERT_EQ(lowest.size(), static_cast<size_t>(sphere.num_vertices()));
  for (int32_t v = 0; v < sphere.num_vertices(); ++v) {
    int32_t first = kNone;
    for (int32_t f = 0; f < sphere.num_faces() && first == kNone; ++f) {
      for (int k = 0; k < 3; ++k) {
        if (sphere.face(f)[k] == v) first = f;
      }
    }
    ASSERT_EQ(lowest[v].face, first) << v;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(lowest[v].w[k], sphere.face(first)[k] == v ? 1.0 : 0.0) << v;
    }
  }
  absl::StatusOr<std::vector<PointPair>> pairs = ParsePairs("v 4 v 9\n0 1 0 0 v 11\n");
  ASSERT_TRUE(pairs.ok()) << pairs.status();
  auto resolve = [&](int32_t v) { return VertexPointOf(lowest, v); };
  ASSERT_TRUE(ResolveVertices(resolve, &*pairs).ok());
  EXPECT_EQ((*pairs)[0].a.face, lowest[4].face);
  EXPECT_EQ((*pairs)[0].b.w, lowest[9].w);
  EXPECT_EQ((*pairs)[1].a.face, 0);
  EXPECT_EQ((*pairs)[1].b.face, lowest[11].face);
  EXPECT_TRUE(ValidatePairs(sphere, *pairs).ok());

  pairs = ParsePairs("0 1 0 0 5 1 0 0\nv 0 v 42\n");
  ASSERT_TRUE(pairs.ok());
  const absl::Status past = ResolveVertices(resolve, &*pairs);
  EXPECT_EQ(past.code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(past.message(), "line 2: vertex id 42 out of range [0, 42)");
  std::vector<SurfacePoint> with_lonely = lowest;
  with_lonely.push_back({kNone, {0, 0, 0}});
  EXPECT_THAT(VertexPointOf(with_lonely, 42).status().message(), HasSubstr("on no face"));
}

}  // namespace
}  // namespace geodex::mesh
