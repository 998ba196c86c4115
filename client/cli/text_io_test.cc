#include "client/cli/text_io.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client::cli {
namespace {

using ::testing::ElementsAre;

TEST(ParsePairs, LinesCommentsAndSeparators) {
  absl::StatusOr<ParsedPairs> parsed = ParsePairs(
      "# header\n"
      "0 1 0 0 5 0.2 0.3 0.5\n"
      "\n"
      "  7,0.5,0.5,0\t9 0 0 1\r\n");
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  ASSERT_EQ(parsed->pairs.size(), 2u);
  EXPECT_THAT(parsed->lines, ElementsAre(2, 4));
  EXPECT_EQ(parsed->pairs[0].b, (SurfacePoint{5, {0.2, 0.3, 0.5}}));
  EXPECT_EQ(parsed->pairs[1].a, (SurfacePoint{7, {0.5, 0.5, 0}}));
}

TEST(ParsePairs, ErrorsNameTheLine) {
  EXPECT_EQ(
      ParsePairs("0 1 0 0 5 0 0 1\n0 1 0 0 5 0 0\n").status(),
      absl::InvalidArgumentError("line 2: expected 8 fields 'fa a0 a1 a2 fb b0 b1 b2', found 7"));
  EXPECT_EQ(ParsePairs("\n\nx 1 0 0 5 0 0 1\n").status(),
            absl::InvalidArgumentError("line 3: field 1 ('x') is not a face id"));
  EXPECT_EQ(ParsePairs("-1 1 0 0 5 0 0 1").status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ParsePairs("0 1 0 0 5 0 nan 1").status(),
            absl::InvalidArgumentError("line 1: field 7 ('nan') is not a finite number"));
  EXPECT_EQ(ParsePairs("0 1 0 0 5 0 0 1x").status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(ParsePairs, VertexIdsStandForPoints) {
  absl::StatusOr<ParsedPairs> parsed = ParsePairs(
      "v 17 v 42\n"
      "v 3 5 0.2 0.3 0.5\n"
      "5 0.2 0.3 0.5 v 0\n");
  ASSERT_TRUE(parsed.ok()) << parsed.status();
  ASSERT_EQ(parsed->pairs.size(), 3u);
  EXPECT_EQ(parsed->pairs[0].a, SurfacePoint::Vertex(17));
  EXPECT_EQ(parsed->pairs[0].b, SurfacePoint::Vertex(42));
  EXPECT_EQ(parsed->pairs[1].b, (SurfacePoint{5, {0.2, 0.3, 0.5}}));
  EXPECT_EQ(parsed->pairs[2].b, SurfacePoint::Vertex(0));
  EXPECT_EQ(FormatPairs(parsed->pairs),
            "v 17 v 42\nv 3 5 0.2 0.3 0.5\n5 0.2 0.3 0.5 v 0\n");
  EXPECT_TRUE(CheckPoint(SurfacePoint::Vertex(99999), 10, 1).ok());
  EXPECT_EQ(ParsePairs("v 17 v\n").status(),
            absl::InvalidArgumentError(
                "line 1: expected 4 fields ('fa a0 a1 a2 fb b0 b1 b2', a point 'v ID' for a "
                "vertex), found 3"));
  EXPECT_EQ(ParsePairs("v -2 v 1\n").status(),
            absl::InvalidArgumentError("line 1: field 2 ('-2') is not a vertex id"));
  absl::StatusOr<ParsedPoints> points = ParsePoints("v 8\n");
  ASSERT_TRUE(points.ok()) << points.status();
  EXPECT_EQ(points->points[0], SurfacePoint::Vertex(8));
}

TEST(ParseOthers, PositionsPointsAndXyzPairs) {
  absl::StatusOr<ParsedPositionPairs> xyz = ParsePositionPairs("1 2 3 4 5 6\n");
  ASSERT_TRUE(xyz.ok());
  EXPECT_EQ(xyz->b[0], (Position{4, 5, 6}));
  EXPECT_EQ(ParsePositionPairs("1 2 3 4 5").status().code(), absl::StatusCode::kInvalidArgument);
  absl::StatusOr<ParsedPoints> points = ParsePoints("3 0.2 0.2 0.6\n");
  ASSERT_TRUE(points.ok());
  EXPECT_EQ(points->points[0].face, 3);
  absl::StatusOr<ParsedPositions> positions = ParsePositions("#c\n1e-3 -2 3.5\n");
  ASSERT_TRUE(positions.ok());
  EXPECT_THAT(positions->lines, ElementsAre(2));
  EXPECT_EQ(positions->positions[0], (Position{1e-3, -2, 3.5}));
}

TEST(CheckPoint, ServerRules) {
  EXPECT_TRUE(CheckPoint({9, {0.2, 0.3, 0.5}}, 10, 1).ok());
  EXPECT_TRUE(CheckPoint({0, {1 + 5e-7, -5e-7, 0}}, 10, 1).ok());
  EXPECT_EQ(CheckPoint({10, {1, 0, 0}}, 10, 4),
            absl::OutOfRangeError("line 4: face 10 is past the end (the model has 10 faces)"));
  EXPECT_EQ(CheckPoint({0, {1.5, -0.5, 0}}, 10, 2).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(CheckPoint({0, {0.5, 0.5, 0.5}}, 10, 2).code(), absl::StatusCode::kInvalidArgument);
}

TEST(FormatPairs, ParsePairsReadsThemBackToTheBit) {
  const std::vector<PointPair> pairs = {
      {{3, {0.1, 0.2, 0.7}}, {0, {1.0 / 3, 1.0 / 3, 1.0 / 3}}},
      {{12, {1, 0, 0}}, {7, {0.123456789012345678, 0.5, 0.376543210987654322}}},
  };
  const std::string text = FormatPairs(pairs);
  EXPECT_EQ(text.substr(0, text.find('\n')), "3 0.1 0.2 0.7 0 0.3333333333333333 0.3333333333333333 0.3333333333333333");
  absl::StatusOr<ParsedPairs> read = ParsePairs(text);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->pairs, pairs);
  EXPECT_EQ(read->lines, (std::vector<int64_t>{1, 2}));
}

TEST(FormatDistance, ShortestRoundTripAndInf) {
  EXPECT_EQ(FormatDistance(1.5), "1.5");
  EXPECT_EQ(FormatDistance(0.1), "0.1");
  EXPECT_EQ(FormatDistance(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(std::stod(FormatDistance(1.0 / 3)), 1.0 / 3);
}

}  // namespace
}  // namespace geodex::client::cli
