#include "core/index/index_report.h"

#include <cmath>
#include <string>

#include "core/index/index_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::index {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using testing_util::MakeSphereIndex;
using testing_util::Serialize;

AccuracyRecord Calibration() {
  AccuracyRecord r{};
  r.scale_length = 0.25f;
  r.num_sources = 64;
  r.num_pairs = 7383;
  r.bound_quantile_permille = 995;
  const float rms[4] = {0.0015f, 0.0058f, 0.015f, 0.018f};
  const float p99[4] = {7.8e-5f, 0.03f, 0.055f, 0.0047f};
  for (int b = 0; b < 4; ++b) {
    r.rms[b] = rms[b];
    r.p99[b] = p99[b];
  }
  r.uniform_rms = 0.0131f;
  r.uniform_far_p99 = 0.0512f;
  return r;
}

std::shared_ptr<const Index> Load(const IndexData& d) {
  auto index = Index::FromBytes(Serialize(d));
  EXPECT_TRUE(index.ok()) << index.status();
  return index.ok() ? *index : nullptr;
}

TEST(IndexReportTest, ParsesKeyValueLinesKeepingTheLastValueAtTheFirstPlace) {
  const auto entries = ParseReportEntries("a = 1\nnot a line\n b =  two words \na = 3\n= 4\n");
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0], std::make_pair(std::string("a"), std::string("3")));
  EXPECT_EQ(entries[1], std::make_pair(std::string("b"), std::string("two words")));
}

TEST(IndexReportTest, FormatsPercentagesWithThreeDigitsAndNoExponent) {
  EXPECT_EQ(FormatPercent(6.42854), "643%");
  EXPECT_EQ(FormatPercent(0.0763931), "7.64%");
  EXPECT_EQ(FormatPercent(0.0131228), "1.31%");
  EXPECT_EQ(FormatPercent(0.00151971), "0.152%");
  EXPECT_EQ(FormatPercent(7.80335e-05), "0.00780%");
  EXPECT_EQ(FormatPercent(0.2), "20.0%");
  EXPECT_EQ(FormatPercent(1e-9), "<0.001%");
  EXPECT_EQ(FormatPercent(0), "0%");
  EXPECT_EQ(FormatPercent(std::nan("")), "n/a");
  EXPECT_EQ(FormatMiB(1612032), "1.54 MiB");
}

TEST(IndexReportTest, FixedMBuildIsComparedWithTheDefaultTarget) {
  IndexData d = MakeSphereIndex();
  d.params.requested_samples = 10;
  d.params.samples_added_by_repair = 2;
  d.accuracy = {Calibration()};
  d.report =
      "mesh_repairs = 0 non-manifold vertices split (0 copies), 2 duplicate faces dropped, "
      "0 zero-area faces and 1 slivers kept\nmesh_duplicate_faces_dropped = 2\n"
      "repair = 2 samples added in 1 rounds\nsamples = 12\n";
  const auto index = Load(d);
  ASSERT_NE(index, nullptr);
  const IndexReport r = MakeIndexReport(*index);
  EXPECT_EQ(r.vertices, 43);
  EXPECT_EQ(r.faces, 80);
  EXPECT_EQ(r.samples, 12);
  EXPECT_EQ(r.requested_samples, 10);
  EXPECT_EQ(r.samples_added_by_repair, 2);
  EXPECT_EQ(r.triangles, 20);
  EXPECT_EQ(r.repairs, "2 duplicate faces dropped, 1 slivers kept");
  ASSERT_EQ(r.repair_counts.size(), 1u);
  EXPECT_EQ(r.repair_counts[0].first, "duplicate_faces_dropped");
  EXPECT_EQ(r.sample_repair, "2 samples added in 1 rounds");
  EXPECT_TRUE(r.error_bounds);
  EXPECT_FALSE(r.target_asked);
  EXPECT_DOUBLE_EQ(r.target_error, kReportDefaultTargetError);
  // Figures are the shortest decimals of the stored floats.
  EXPECT_EQ(r.bins[1].p99, 0.03);
  EXPECT_EQ(r.bins[2].rms, 0.015);
  EXPECT_EQ(r.scale_length, 0.25);
  EXPECT_DOUBLE_EQ(r.bins[0].p99_limit, 0.01);
  EXPECT_DOUBLE_EQ(r.bins[3].p99_limit, 0.02);
  EXPECT_TRUE(std::isinf(r.bins[3].to_l));
  // An index without the judged checks or the L1000 bands: its uniform RMS
  // is what today's target judges of it; bins by L are not judged.
  EXPECT_EQ(r.target_verdict,
            "none asked (a fixed m, 10 requested); measured against the default target "
            "0.500%: the uniform RMS over the limit");
  // The sections add up to the file.
  uint64_t total = 0;
  for (const ReportSection& s : r.sections) total += s.bytes;
  EXPECT_EQ(total, index->size_bytes());
  EXPECT_EQ(r.sections[0].key, "mesh");  // largest first

  const std::string text = IndexReportText(r, "sphere.gdx");
  EXPECT_THAT(text, HasSubstr("sphere.gdx: geodex index, format 1.3"));
  EXPECT_THAT(text, HasSubstr("m = 12: 10 requested, 2 added"));
  EXPECT_THAT(text, HasSubstr("\n                  L-3L          0.580%     3.00%\n"));
  EXPECT_THAT(text, HasSubstr("\n                  d < L         0.150%  0.00780%\n"));
  EXPECT_THAT(text, HasSubstr("(L = 0.25, the index's sample spacing; this index has no L1000"));
  EXPECT_THAT(text, HasSubstr("area-uniform pairs: RMS 1.31% (limit 0.500%)\n"));
  EXPECT_THAT(text, Not(HasSubstr("  over")));  // no limit on a bin the target does not judge
  EXPECT_THAT(text, HasSubstr("2 duplicate faces dropped"));
  EXPECT_THAT(text, Not(HasSubstr("e-0")));  // no exponents for a person

  const std::string json = IndexReportJson(r);
  EXPECT_THAT(json, HasSubstr("\"key\": \"L_3L\", \"label\": \"L-3L\", \"from_L\": 1, \"to_L\": 3, "
                              "\"rms\": 0.0058, \"p99\": 0.03, \"p99_limit\": 0.01}"));
  EXPECT_THAT(json, HasSubstr("\"to_L\": null"));
  EXPECT_THAT(json, HasSubstr("\"asked\": false"));
  EXPECT_THAT(json, HasSubstr("\"met\": null"));
  EXPECT_THAT(json, HasSubstr("\"faces\": 80,"));
  EXPECT_THAT(json, HasSubstr("\"samples\": \"12\""));  // the stored lines, verbatim
}

TEST(IndexReportTest, TargetBuildSaysWhyTheTargetWasNotMet) {
  IndexData d = MakeSphereIndex();
  d.accuracy = {Calibration()};
  d.report =
      "target_error = 0.005\ntarget_error_reached = no (the cap of 300 samples)\n"
      "target_error_rounds = 2\ntarget_error_round_1 = m = 200: uniform RMS 1% (1.2%) / 0.5%\n"
      "target_error_round_2 = m = 300: uniform RMS 1% (1.2%) / 0.5%\n"
      "target_error_worst = vertex 3L-10L p99 0.064817 of 0.02\n";
  const auto index = Load(d);
  ASSERT_NE(index, nullptr);
  const IndexReport r = MakeIndexReport(*index);
  EXPECT_TRUE(r.target_asked);
  EXPECT_FALSE(r.target_met);
  EXPECT_EQ(r.target_stop, "the cap of 300 samples");
  EXPECT_EQ(r.target_rounds, (std::vector<int64_t>{200, 300}));
  EXPECT_EQ(r.closest_check, "vertex 3L-10L p99");
  EXPECT_DOUBLE_EQ(r.closest_upper95, 0.064817);
  EXPECT_DOUBLE_EQ(r.closest_limit, 0.02);
  EXPECT_EQ(r.target_verdict,
            "0.500% NOT met: m stopped at the cap of 300 samples after 2 rounds (m = 200, 300); "
            "the furthest check, vertex 3L-10L p99, has a 95% upper limit of 6.48% against 2.00%");
  EXPECT_THAT(IndexReportJson(r), HasSubstr("\"met\": false"));
  EXPECT_THAT(IndexReportJson(r), HasSubstr("\"rounds\": [200, 300]"));
}

TEST(IndexReportTest, IndexWithoutCalibrationHasNoAccuracy) {
  IndexData d = MakeSphereIndex();
  d.report.clear();
  const auto index = Load(d);
  ASSERT_NE(index, nullptr);
  const IndexReport r = MakeIndexReport(*index);
  EXPECT_FALSE(r.has_accuracy);
  EXPECT_EQ(r.repairs, "none recorded");
  EXPECT_THAT(r.target_verdict, HasSubstr("no calibration"));
  const std::string text = IndexReportText(r, "x");
  EXPECT_THAT(text, HasSubstr("error bounds  no (geodex-build calibrate adds them)"));
  EXPECT_THAT(text, Not(HasSubstr("accuracy")));
  EXPECT_THAT(IndexReportJson(r), HasSubstr("\"accuracy\": null"));
  EXPECT_THAT(IndexReportJson(r), HasSubstr("\"build_report\": {}"));
}

// A 6.0 file says what it leaves out for the reader to derive; an older one
// stores everything.
TEST(IndexReportTest, SaysWhatTheReaderDerivesAtLoad) {
  IndexData d = MakeSphereIndex();
  d.sample_matrix = MatrixLayout::kCoded;
  const auto index = Load(d);
  ASSERT_NE(index, nullptr);
  const IndexReport r = MakeIndexReport(*index);
  EXPECT_EQ(r.derived_at_load, (std::vector<std::string>{"twins", "face BVH"}));
  EXPECT_THAT(IndexReportText(r, "x"), HasSubstr("twins, face BVH: not stored, derived at load"));
  EXPECT_THAT(IndexReportJson(r), HasSubstr("\"derived_at_load\": [\"twins\", \"face BVH\"]"));
  d.coded_as_version_5 = true;
  const auto older = Load(d);
  ASSERT_NE(older, nullptr);
  EXPECT_TRUE(MakeIndexReport(*older).derived_at_load.empty());
  EXPECT_THAT(IndexReportJson(MakeIndexReport(*older)), HasSubstr("\"derived_at_load\": []"));
}

}  // namespace
}  // namespace geodex::index
