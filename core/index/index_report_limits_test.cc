// The report's limits are the error target's (core/validation/target_error.h),
// which the index library cannot include: the report is read where the
// validation is not linked.

#include "core/index/index_report.h"

#include <cmath>

#include "core/index/index_test_util.h"
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

}  // namespace
}  // namespace geodex::index
