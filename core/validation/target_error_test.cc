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

int FarCheck(int kind) { return 1 + kind; }

TEST(TargetErrorTest, LimitsAndNames) {
  EXPECT_EQ(TargetLimit(0, kE), kE);
  EXPECT_EQ(TargetLimit(FarCheck(BinConfidence::kVertex), kE), 4 * kE);
  EXPECT_EQ(TargetLimit(FarCheck(BinConfidence::kInterior), kE), 4 * kE);
  EXPECT_EQ(TargetCheckName(0), "uniform RMS");
  EXPECT_EQ(TargetCheckName(FarCheck(BinConfidence::kVertex)), "vertex >=8 L1000 p99");
  EXPECT_EQ(TargetCheckName(FarCheck(BinConfidence::kInterior)), "interior >=8 L1000 p99");
}

TEST(TargetErrorTest, EveryJudgedCheckMustBeMetByItsUpperLimit) {
  TargetFigures f = AtShare(1000, 0.99);
  EXPECT_TRUE(TargetMet(f, kE));
  EXPECT_NEAR(Distance(f, kE), 0.99, 1e-12);
  // One check over its limit by its upper confidence limit fails the
  // target, even when its measured p99 is under it.
  const int c = FarCheck(BinConfidence::kInterior);
  f.upper[c] = 1.01 * TargetLimit(c, kE);
  f.measured[c] = 0.9 * TargetLimit(c, kE);
  EXPECT_FALSE(TargetMet(f, kE));
  EXPECT_EQ(WorstCheck(f, kE), c);
  EXPECT_NEAR(Distance(f, kE), 1.01, 1e-12);
  EXPECT_NE(FiguresText(f, kE).find("interior >=8 L1000 p99"), std::string::npos);
  EXPECT_NE(FiguresText(f, kE).find("MISSED"), std::string::npos);
  // A check without pairs (a surface too small for pairs 8 L1000 apart) is
  // not judged.
  f.pairs[c] = 0;
  EXPECT_TRUE(TargetMet(f, kE));
}

// The sequential validation's stopping rule: a round far under every limit
// or beyond doubt over one is settled; one whose upper limits come within
// kSettledShare of a limit, met or not, draws more sources.
TEST(TargetErrorTest, SettledFarFromTheLimitsAndUndecidedNearThem) {
  EXPECT_TRUE(TargetSettled(AtShare(1000, 0.5), kE));
  EXPECT_TRUE(TargetSettled(AtShare(1000, kSettledShare), kE));
  EXPECT_FALSE(TargetSettled(AtShare(1000, 0.95), kE));  // met, but only just
  EXPECT_TRUE(TargetMet(AtShare(1000, 0.95), kE));
  EXPECT_FALSE(TargetSettled(AtShare(1000, 1.05), kE));  // missed, but not beyond doubt
  // Measured over the limit with a lower limit (2 measured - upper) over it too.
  TargetFigures f = AtShare(1000, 0.5);
  const int c = FarCheck(BinConfidence::kVertex);
  f.measured[c] = 1.2 * TargetLimit(c, kE);
  f.upper[c] = 1.3 * TargetLimit(c, kE);
  EXPECT_TRUE(TargetSettled(f, kE));
  // Measured over it, but within the margin of noise: not settled.
  f.upper[c] = 1.5 * TargetLimit(c, kE);
  EXPECT_FALSE(TargetSettled(f, kE));
  // A check without pairs is not judged.
  f.pairs[c] = 0;
  EXPECT_TRUE(TargetSettled(f, kE));
}

TEST(TargetErrorTest, BandsAreReportedNotJudged) {
  TargetFigures f = AtShare(1000, 0.5);
  f.unit = 0.01;
  f.band_p99[BinConfidence::kInterior][3] = 0.04;  // 2-4 L1000: 4%, over any limit
  f.band_pairs[BinConfidence::kInterior][3] = 300;
  EXPECT_TRUE(TargetMet(f, kE));
  EXPECT_NE(BandsLine(f).find("2-4 - / 4.00%"), std::string::npos) << BandsLine(f);
  // The bands' keys for the report, with the refinement's threshold in
  // L1000 (kRefineScale of the index's own L).
  const std::string text = BandsText(f, 0.005);
  EXPECT_NE(text.find("band_unit = 0.01\n"), std::string::npos) << text;
  EXPECT_NE(text.find("band_p99_interior_2_4 = 0.04\n"), std::string::npos) << text;
  EXPECT_NE(text.find("band_pairs_interior_2_4 = 300\n"), std::string::npos) << text;
  EXPECT_NE(text.find("band_pairs_vertex_16_inf = 0\n"), std::string::npos) << text;
}

TEST(TargetErrorTest, PredictionFromTheRatesTheFiguresFallAt) {
  // The far band at 1.62x its limit: its p99 falls as m^-0.8, so it asks
  // (1.62 / 0.9)^(1 / 0.8) = 2.08x the samples.
  TargetFigures f = AtShare(500, 0.5);
  const int c = FarCheck(BinConfidence::kVertex);
  f.upper[c] = 1.62 * TargetLimit(c, kE);
  std::vector<TargetFigures> rounds = {f};
  EXPECT_NEAR(PredictSamples(rounds, kE, 100000), 500 * std::pow(1.8, 1 / 0.8), 1);
  // The RMS at 1.62x: it falls as m^-0.7, 1.8^(1/0.7) = 2.32x.
  TargetFigures g = AtShare(500, 0.5);
  g.upper[0] = 1.62 * kE;
  rounds = {g};
  EXPECT_NEAR(PredictSamples(rounds, kE, 100000), 500 * std::pow(1.8, 1 / 0.7), 1);
  // The last round decides.
  rounds = {AtShare(250, 5), f};
  EXPECT_NEAR(PredictSamples(rounds, kE, 100000), 500 * std::pow(1.8, 1 / 0.8), 1);
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
  // An index of exactly its coded lower triangle: m (m - 1) / 2 codes of
  // 3 bytes.
  const int64_t budget = kMaxIndexBytes;
  auto matrix = [](int64_t m) { return 3 * m * (m - 1) / 2; };
  const int32_t m = SamplesWithinBytes(budget, 1000, matrix(1000));
  EXPECT_LE(matrix(m), budget);
  EXPECT_GT(matrix(m + 1), budget);
  EXPECT_NEAR(m, 4730, 1);
  // 4 kB a sample beside the matrix leaves room for fewer.
  const int32_t fewer = SamplesWithinBytes(budget, 1000, matrix(1000) + 4000 * 1000);
  EXPECT_LE(matrix(fewer) + int64_t{4000} * fewer, budget);
  EXPECT_GT(matrix(fewer + 1) + int64_t{4000} * (fewer + 1), budget);
  EXPECT_LT(fewer, m);
}

}  // namespace
}  // namespace geodex::validation
