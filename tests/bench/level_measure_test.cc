#include "tests/bench/level_measure.h"

#include "gtest/gtest.h"

namespace geodex::bench {
namespace {

TEST(LevelMeasureTest, BinsDoubleFromTheirFirstEdge) {
  EXPECT_EQ(RatioBin(0.5), 0);
  EXPECT_EQ(RatioBin(1), 1);
  EXPECT_EQ(RatioBin(3.99), 2);
  EXPECT_EQ(RatioBin(4), 3);
  EXPECT_EQ(RatioBin(1e9), kNumRatioBins - 1);
  EXPECT_EQ(RatioBinName(0), "[0,1)");
  EXPECT_EQ(RatioBinName(3), "[4,8)");
  EXPECT_EQ(RatioBinName(kNumRatioBins - 1), ">=64");
  EXPECT_EQ(FixedBin(0.49), 0);
  EXPECT_EQ(FixedBin(0.5), 1);
  EXPECT_EQ(FixedBin(17), kNumFixedBins - 1);
  EXPECT_EQ(FixedBinName(2), "[1,2)");
  EXPECT_EQ(FixedBinName(kNumFixedBins - 1), ">=16");
}

TEST(LevelMeasureTest, ErrorsGoToTheirKindAndBins) {
  std::vector<validation::ExactPair> pairs(3);
  pairs[0].exact = 1.5, pairs[0].vertices = true;  // d/L 1.5, d/L1000 0.75
  pairs[1].exact = 10, pairs[1].vertices = false;  // d/L 10, d/L1000 5
  pairs[2].exact = 0;                              // left out
  const LevelErrors e = BinErrors(pairs, {1.65, 9, 3}, 1.0, 2.0);
  ASSERT_EQ(e.by_ratio[0][1].size(), 1u);
  EXPECT_NEAR(e.by_ratio[0][1][0], 0.1, 1e-12);
  ASSERT_EQ(e.by_ratio[1][4].size(), 1u);
  EXPECT_NEAR(e.by_ratio[1][4][0], -0.1, 1e-12);
  EXPECT_EQ(e.by_fixed[0][1].size(), 1u);
  EXPECT_EQ(e.by_fixed[1][4].size(), 1u);
  EXPECT_EQ(RatioRow("x", e, 1).substr(0, 16), "| x | - / - | 10");
  EXPECT_DOUBLE_EQ(TableBytesPerSample(100, 6), 300);
}

}  // namespace
}  // namespace geodex::bench
