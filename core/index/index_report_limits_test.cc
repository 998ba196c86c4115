// The report's limits are the error target's (core/validation/target_error.h),
// which the index library cannot include: the report is read where the
// validation is not linked.

#include "core/index/index_report.h"

#include <cmath>

#include "core/index/index_testing.h"
#include "core/validation/target_error.h"
#include "gtest/gtest.h"

namespace geodex::index {
namespace {

TEST(IndexReportLimitsTest, AreTheErrorTargets) {
  EXPECT_EQ(kReportDefaultTargetError, validation::kDefaultTargetError);
  IndexData d = testing_util::MakeSphereIndex();
  d.report = "target_error = 0.003\nband_unit = 0.01\nband_refined_below = 2.5\n";
  auto index = Index::FromBytes(testing_util::Serialize(d));
  ASSERT_TRUE(index.ok()) << index.status();
  const IndexReport r = MakeIndexReport(**index);
  ASSERT_TRUE(r.target_asked);
  ASSERT_EQ(r.bands.size(), size_t{validation::kNumFixedBins});
  // The bands from 8 L1000 are judged as the target's far checks (1: vertex
  // pairs, 2: interior pairs, the same limit); the closer ones are reported
  // only, and say how the default mode answers them.
  for (int b = 0; b < validation::kNumFixedBins; ++b) {
    const ReportBand& band = r.bands[b];
    EXPECT_EQ(band.label, validation::FixedBinName(b));
    EXPECT_EQ(band.from, validation::FixedBinLower(b));
    if (band.from >= 8) {
      EXPECT_DOUBLE_EQ(band.p99_limit, validation::TargetLimit(1, 0.003)) << band.label;
      EXPECT_DOUBLE_EQ(band.p99_limit, validation::TargetLimit(2, 0.003)) << band.label;
    } else {
      EXPECT_TRUE(std::isnan(band.p99_limit)) << band.label;
    }
  }
  EXPECT_EQ(r.bands[2].answer, "walked or exact");  // [1, 2) L1000
  EXPECT_EQ(r.bands[3].answer, "walked or exact below 2.5, O(1) above");
  EXPECT_EQ(r.bands[4].answer, "O(1)");  // [4, 8) L1000
}

// The judged checks the build stores (BandsText) are the ones the report
// reads, with the target's names and limits: the verdict and the "judged"
// lines are the build's own measurement.
TEST(IndexReportLimitsTest, ChecksAreTheTargetsChecks) {
  validation::TargetFigures f;
  f.unit = 0.01;
  for (int c = 0; c < validation::kNumTargetChecks; ++c) {
    f.measured[c] = 0.001 * (c + 1);
    f.upper[c] = 0.0015 * (c + 1);
    f.pairs[c] = 100 * (c + 1);
  }
  f.upper[2] = 0.05;  // the interior far check over 4E
  IndexData d = testing_util::MakeSphereIndex();
  AccuracyRecord calibration{};
  calibration.scale_length = 0.02f;
  calibration.num_sources = 8;
  calibration.num_pairs = 600;
  d.accuracy = {calibration};
  d.report = "target_error = 0.004\n" + validation::BandsText(f, 0.02);
  auto index = Index::FromBytes(testing_util::Serialize(d));
  ASSERT_TRUE(index.ok()) << index.status();
  const IndexReport r = MakeIndexReport(**index);
  ASSERT_EQ(r.checks.size(), size_t{validation::kNumTargetChecks});
  for (int c = 0; c < validation::kNumTargetChecks; ++c) {
    EXPECT_EQ(r.checks[c].label, validation::TargetCheckName(c));
    EXPECT_DOUBLE_EQ(r.checks[c].limit, validation::TargetLimit(c, 0.004));
    EXPECT_DOUBLE_EQ(r.checks[c].measured, f.measured[c]);
    EXPECT_DOUBLE_EQ(r.checks[c].upper95, f.upper[c]);
    EXPECT_EQ(r.checks[c].pairs, f.pairs[c]);
  }
  const std::string text = IndexReportText(r, "x.gdx");
  EXPECT_NE(text.find("interior >=8 L1000 p99      0.300% (5.00% / 1.60%)  over"),
            std::string::npos)
      << text;
  EXPECT_NE(IndexReportJson(r).find("\"key\": \"interior_far_p99\""), std::string::npos);
}

}  // namespace
}  // namespace geodex::index
