#include "core/validation/target_error.h"

#include <cmath>
#include <vector>

#include "gtest/gtest.h"

namespace geodex::validation {
namespace {

constexpr double kE = 0.005;

// Figures of `m` samples with every check at `share` of its limit.
TargetFigures AtShare(int32_t m, double share) {
  TargetFigures f;
  f.samples = m;
  for (int c = 0; c < kNumTargetChecks; ++c) {
    f.upper[c] = share * TargetLimit(c, kE);
    f.measured[c] = 0.8 * f.upper[c];
    f.pairs[c] = 500;
  }
  return f;
}

int Check(int kind, int bin) { return 1 + kind * kNumScaleBins + bin; }

TEST(TargetErrorTest, LimitsByBin) {
  EXPECT_EQ(TargetLimit(0, kE), kE);
  for (int kind = 0; kind < 2; ++kind) {
    EXPECT_EQ(TargetLimit(Check(kind, 0), kE), 2 * kE);  // d < L
    EXPECT_EQ(TargetLimit(Check(kind, 1), kE), 2 * kE);  // L-3L
    EXPECT_EQ(TargetLimit(Check(kind, 2), kE), 4 * kE);  // 3L-10L
    EXPECT_EQ(TargetLimit(Check(kind, 3), kE), 4 * kE);  // >= 10L
  }
  EXPECT_EQ(TargetCheckName(0), "uniform RMS");
  EXPECT_EQ(TargetCheckName(Check(BinConfidence::kVertex, 2)), "vertex 3L-10L p99");
  EXPECT_EQ(TargetCheckName(Check(BinConfidence::kInterior, 3)), "interior >=10L p99");
}

TEST(TargetErrorTest, EveryJudgedCheckMustBeMetByItsUpperLimit) {
  TargetFigures f = AtShare(1000, 0.99);
  EXPECT_TRUE(TargetMet(f, kE));
  // One bin over its limit by its upper confidence limit fails the target,
  // even when its measured p99 is under it.
  const int c = Check(BinConfidence::kInterior, 2);
  f.upper[c] = 1.01 * TargetLimit(c, kE);
  f.measured[c] = 0.9 * TargetLimit(c, kE);
  EXPECT_FALSE(TargetMet(f, kE));
  EXPECT_EQ(WorstCheck(f, kE), c);
  EXPECT_NE(FiguresText(f, kE).find("interior 3L-10L p99"), std::string::npos);
  EXPECT_NE(FiguresText(f, kE).find("MISSED"), std::string::npos);
  // A bin without pairs is not judged.
  f.pairs[c] = 0;
  EXPECT_TRUE(TargetMet(f, kE));
}

TEST(TargetErrorTest, PredictionFromTheRatesTheFiguresFallAt) {
  // A bin at 1.62x its limit: a bin's p99 falls as m^-0.6, so it asks
  // (1.62 / 0.9)^(1 / 0.6) = 2.66x the samples.
  TargetFigures f = AtShare(500, 0.5);
  const int c = Check(BinConfidence::kVertex, 2);
  f.upper[c] = 1.62 * TargetLimit(c, kE);
  std::vector<TargetFigures> rounds = {f};
  EXPECT_NEAR(PredictSamples(rounds, kE, 100000), 500 * std::pow(1.8, 1 / 0.6), 1);
  // The RMS at 1.62x: it falls as m^-0.7, 1.8^(1/0.7) = 2.32x.
  TargetFigures g = AtShare(500, 0.5);
  g.upper[0] = 1.62 * kE;
  rounds = {g};
  EXPECT_NEAR(PredictSamples(rounds, kE, 100000), 500 * std::pow(1.8, 1 / 0.7), 1);
  // The last round decides.
  rounds = {AtShare(250, 5), f};
  EXPECT_NEAR(PredictSamples(rounds, kE, 100000), 500 * std::pow(1.8, 1 / 0.6), 1);
  // Growth at least 1.2x and at most 3x, and never past the cap.
  TargetFigures barely = AtShare(1000, 0.5);
  barely.upper[0] = 1.0001 * kE;  // (1.0001 / 0.9)^(1 / 0.7) = 1.16
  rounds = {barely};
  EXPECT_EQ(PredictSamples(rounds, kE, 100000), 1200);
  rounds = {AtShare(1000, 50)};
  EXPECT_EQ(PredictSamples(rounds, kE, 100000), 3000);
  EXPECT_EQ(PredictSamples(rounds, kE, 2500), 2500);
}

TEST(TargetErrorTest, SamplesWithinBytesCountsTheMatrixAndThePerSampleRest) {
  // An index of exactly its packed matrix: m^2 - m = budget / 2.
  const int64_t budget = kMaxIndexBytes;
  const int32_t m = SamplesWithinBytes(budget, 1000, 2 * int64_t{1000} * 999);
  EXPECT_LE(2 * int64_t{m} * (m - 1), budget);
  EXPECT_GT(2 * int64_t{m + 1} * m, budget);
  EXPECT_NEAR(m, 5793, 1);
  // 4 kB a sample beside the matrix leaves room for fewer.
  const int32_t fewer = SamplesWithinBytes(budget, 1000, 2 * int64_t{1000} * 999 + 4000 * 1000);
  EXPECT_LE(2 * int64_t{fewer} * (fewer - 1) + int64_t{4000} * fewer, budget);
  EXPECT_GT(2 * int64_t{fewer + 1} * fewer + int64_t{4000} * (fewer + 1), budget);
  EXPECT_LT(fewer, m);
}

}  // namespace
}  // namespace geodex::validation
