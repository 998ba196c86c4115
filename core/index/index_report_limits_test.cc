// The report's limits are the error target's (core/validation/target_error.h),
// which the index library cannot include: the report is read where the
// validation is not linked.

#include "core/index/index_report.h"
#include "core/index/index_test_util.h"
#include "core/validation/target_error.h"
#include "gtest/gtest.h"

namespace geodex::index {
namespace {

TEST(IndexReportLimitsTest, AreTheErrorTargets) {
  EXPECT_EQ(kReportDefaultTargetError, validation::kDefaultTargetError);
  IndexData d = testing_util::MakeSphereIndex();
  d.report = "target_error = 0.003\n";
  auto index = Index::FromBytes(testing_util::Serialize(d));
  ASSERT_TRUE(index.ok()) << index.status();
  const IndexReport r = MakeIndexReport(**index);
  ASSERT_TRUE(r.target_asked);
  // Checks 1..4 are the vertex pairs' p99 by bin, in the report's bin order.
  for (int b = 0; b < 4; ++b) {
    EXPECT_DOUBLE_EQ(r.bins[b].p99_limit, validation::TargetLimit(1 + b, 0.003))
        << validation::TargetCheckName(1 + b);
  }
}

}  // namespace
}  // namespace geodex::index
