#include <sstream>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/bench/bench_flags.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/bench_timing.h"

namespace geodex::bench {
namespace {

using ::testing::HasSubstr;

// A program with one option, --count.
class ParseFlagsTest : public ::testing::Test {
 protected:
  ParseFlagsTest() { app_.add_option("--count", count_, "How many"); }

  CLI::App app_{"a test program"};
  int count_ = 1;
  std::ostringstream out_, err_;
};

TEST_F(ParseFlagsTest, GoesOnAfterGoodFlags) {
  EXPECT_EQ(ParseFlags(app_, {"prog", "--count", "7"}, out_, err_), std::nullopt);
  EXPECT_EQ(count_, 7);
  EXPECT_EQ(out_.str(), "");
  EXPECT_EQ(err_.str(), "");
}

TEST_F(ParseFlagsTest, HelpExitsZeroWithTheHelpOnOut) {
  EXPECT_EQ(ParseFlags(app_, {"prog", "--help"}, out_, err_), 0);
  EXPECT_THAT(out_.str(), HasSubstr("a test program"));
  EXPECT_THAT(out_.str(), HasSubstr("--count INT"));
  EXPECT_EQ(err_.str(), "");
}

TEST_F(ParseFlagsTest, ABadValueExitsNonZeroWithTheErrorOnErr) {
  const std::optional<int> code = ParseFlags(app_, {"prog", "--count", "x"}, out_, err_);
  ASSERT_TRUE(code.has_value());
  EXPECT_NE(*code, 0);
  EXPECT_THAT(err_.str(), HasSubstr("--count"));
}

TEST_F(ParseFlagsTest, AnUnknownFlagExitsNonZero) {
  const std::optional<int> code = ParseFlags(app_, {"prog", "--nope"}, out_, err_);
  ASSERT_TRUE(code.has_value());
  EXPECT_NE(*code, 0);
  EXPECT_THAT(err_.str(), HasSubstr("--nope"));
}

TEST(MarkdownTest, RowSeparatesCellsWithBars) {
  EXPECT_EQ(MarkdownRow({"a", "b c", "1.5"}), "| a | b c | 1.5 |");
  EXPECT_EQ(MarkdownRow({}), "|");
}

TEST(MarkdownTest, HeaderHasOneRuleCellPerColumn) {
  EXPECT_EQ(MarkdownHeader({"x", "y", "z"}), "| x | y | z |\n|---|---|---|\n");
  EXPECT_EQ(MarkdownHeader({"x", "y", "z"}, "lr"), "| x | y | z |\n|---|---:|---|\n");
}

TEST(TimingTest, PercentileIsTheNearestRank) {
  const std::vector<double> v = {5, 1, 4, 2, 3};
  EXPECT_EQ(Percentile(v, 0), 1);
  EXPECT_EQ(Percentile(v, 0.5), 3);
  EXPECT_EQ(Percentile(v, 0.99), 5);
  EXPECT_EQ(Percentile(v, 1), 5);
  EXPECT_EQ(Percentile({7}, 0.5), 7);
}

TEST(TimingTest, MeanOfTheFirstN) {
  const std::vector<double> v = {1, 2, 3, 10};
  EXPECT_DOUBLE_EQ(Mean(v, 3), 2);
  EXPECT_DOUBLE_EQ(Mean(v, 100), 4);
  EXPECT_EQ(Mean(v, 0), 0);
  EXPECT_EQ(Mean({}, 3), 0);
}

TEST(TimingTest, ClocksDoNotGoBack) {
  const double thread0 = ThreadCpuSeconds(), process0 = ProcessCpuSeconds();
  const Clock::time_point start = Clock::now();
  volatile double sink = 0;
  for (int i = 0; i < 100000; ++i) sink = sink + i;
  EXPECT_GE(ThreadCpuSeconds(), thread0);
  EXPECT_GE(ProcessCpuSeconds(), process0);
  EXPECT_GE(SecondsSince(start), 0);
  EXPECT_EQ(SecondsBetween(start, start), 0);
  EXPECT_DOUBLE_EQ(SecondsBetween(start, start + std::chrono::milliseconds(1500)), 1.5);
}

}  // namespace
}  // namespace geodex::bench
