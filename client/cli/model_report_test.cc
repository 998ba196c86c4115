#include "client/cli/model_report.h"

#include <string>

#include "client/cli/outputs.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client::cli {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

// A report as core/index/index_report.h writes it (abridged).
// clang-format off
constexpr char kReport[] = R"json({
  "format": "2.1",
  "builder": "geodex-build 0.1.0",
  "mesh": {
    "vertices": 250,
    "faces": 500,
    "index_vertices": 3305,
    "index_faces": 6610,
    "split_midpoints": 3055,
    "repairs": "none",
    "repair_counts": {"faces_reoriented": 0}
  },
  "samples": {"requested": 300, "final": 300, "added_by_repair": 0, "repair": "0 samples added in 0 rounds"},
  "triangles": 600,
  "size": {"bytes": 1150656, "sections": [
    {"key": "distance_matrix", "label": "distance matrix", "bytes": 360000},
    {"key": "calibration", "label": "calibration", "bytes": 376}]},
  "error_bounds": true,
  "target": {
    "error": 0.005,
    "asked": true,
    "met": false,
    "stop": "the cap of 300 samples",
    "rounds": [300],
    "closest_check": "vertex 3L-10L p99",
    "closest_upper95": 0.064817,
    "closest_limit": 0.02,
    "checks": [
      {"key": "uniform_rms", "label": "uniform RMS", "measured": 0.0125, "upper95": 0.0131, "limit": 0.005, "pairs": 8000},
      {"key": "vertex_far_p99", "label": "vertex >=8 L1000 p99", "measured": 0.0503, "upper95": 0.064817, "limit": 0.02, "pairs": 900},
      {"key": "interior_far_p99", "label": "interior >=8 L1000 p99", "measured": 0.0139, "upper95": 0.0151, "limit": 0.02, "pairs": 870}
    ],
    "verdict": "0.500% NOT met: m stopped at the cap of 300 samples after 1 round (m = 300)"
  },
  "accuracy": {
    "sources": 128,
    "pairs": 14765,
    "scale_length": 0.14864576,
    "uniform_rms": 0.012520552,
    "uniform_far_p99": 0.047317427,
    "bins": [
      {"key": "below_L", "label": "d < L", "from_L": 0, "to_L": 1, "rms": 0.00017556928, "p99": 1.6596281e-15, "p99_limit": 0.01},
      {"key": "beyond_10L", "label": ">= 10L", "from_L": 10, "to_L": null, "rms": 0.014184382, "p99": 0.04691552, "p99_limit": 0.02}
    ],
    "band_unit": 0.2525,
    "refined_below": 9.49,
    "bands": [
      {"key": "1_2", "label": "1-2", "from": 1, "to": 2, "p99_vertex": 0.0000001, "p99_interior": null, "pairs_vertex": 40, "pairs_interior": 0, "p99_limit": null, "answer": "walked or exact"},
      {"key": "8_16", "label": "8-16", "from": 8, "to": 16, "p99_vertex": 0.0503, "p99_interior": 0.0139, "pairs_vertex": 900, "pairs_interior": 870, "p99_limit": 0.02, "answer": "walked or exact below 9.49, O(1) above"}
    ]
  },
  "build_report": {
    "samples": "300"
  }
}
)json";
// clang-format on

ModelInfo Model() {
  ModelInfo m;
  m.name = "bob";
  m.version = 3;
  m.state = ModelInfo::State::kServing;
  m.report_json = kReport;
  return m;
}

TEST(ModelReportTest, LaysOutTheServersReport) {
  const absl::StatusOr<std::string> text = ModelReportText(Model());
  ASSERT_TRUE(text.ok()) << text.status();
  EXPECT_THAT(*text, HasSubstr("model bob, version 3 (SERVING): geodex index, format 2.1, built "
                               "by geodex-build 0.1.0\n"));
  EXPECT_THAT(*text, HasSubstr("  mesh          250 vertices, 500 faces (answered on 3305 "
                               "vertices, 6610 faces)\n"));
  EXPECT_THAT(*text, HasSubstr("  split         3055 midpoints (long edges split flat)\n"));
  EXPECT_THAT(*text, HasSubstr("                  distance matrix            0.34 MiB  31.3%\n"));
  EXPECT_THAT(*text, HasSubstr("                  calibration               0.000 MiB  <0.1%\n"));
  EXPECT_THAT(*text, HasSubstr("  error target  0.500% NOT met: m stopped at the cap"));
  EXPECT_THAT(*text, HasSubstr("  samples       m = 300 (chosen by the target; rounds m = 300), 0 "
                               "added by the repair of the\n                triangulation\n"));
  // The fixed L1000 bands, as core/index/index_report.cc lays them out: no
  // limit on a row, the judged checks below, the index's own L only where
  // it sets the walked / O(1) split.
  EXPECT_THAT(
      *text,
      HasSubstr("                  1-2          <0.001%       n/a  -         walked or exact\n"));
  EXPECT_THAT(*text, HasSubstr("                  8-16           5.03%     1.39%  judged    walked "
                               "or exact below 9.49, O(1) above\n"));
  EXPECT_THAT(
      *text,
      HasSubstr("                  vertex >=8 L1000 p99         5.03% (6.48% / 2.00%)  over\n"));
  EXPECT_THAT(*text,
              HasSubstr("                  interior >=8 L1000 p99       1.39% (1.51% / 2.00%)\n"));
  EXPECT_THAT(*text, HasSubstr("L1000 = 0.2525, the spacing of 1000 samples on this surface"));
  EXPECT_THAT(*text,
              HasSubstr("below 9.49 L1000 (16.1 L,\n                where L = 0.1486 is this "
                        "index's own sample spacing), O(1) above.\n"));
  EXPECT_THAT(*text, Not(HasSubstr("10L")));  // the bins by L: not shown beside the bands
  EXPECT_THAT(*text, Not(HasSubstr("p99 limit")));
}

// A 6.0 index's report lists the sections the server derived at load; an
// older one (above) has no such list and prints no such line.
TEST(ModelReportTest, SaysWhatTheServerDerivedAtLoad) {
  ModelInfo m = Model();
  const std::string sections = R"("bytes": 376}]})";
  const size_t at = m.report_json.find(sections);
  ASSERT_NE(at, std::string::npos);
  m.report_json.replace(at, sections.size(),
                        R"("bytes": 376}], "derived_at_load": ["twins", "face BVH"]})");
  const absl::StatusOr<std::string> text = ModelReportText(m);
  ASSERT_TRUE(text.ok()) << text.status();
  EXPECT_THAT(*text, HasSubstr("                  calibration               0.000 MiB  <0.1%\n"
                               "                  twins, face BVH: not stored, derived at load\n"));
  EXPECT_THAT(*ModelReportText(Model()), Not(HasSubstr("derived at load")));
}

TEST(ModelReportTest, RefusesAMalformedReport) {
  ModelInfo m = Model();
  m.report_json = "[1, 2]";
  EXPECT_EQ(ModelReportText(m).status().code(), absl::StatusCode::kInvalidArgument);
  m.report_json = R"({"format": "2.1"})";
  EXPECT_EQ(ModelReportText(m).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(ModelReportTest, WithoutTheReportShowsTheKeyValues) {
  ModelInfo m = Model();
  m.report_json.clear();
  m.num_faces = 500;
  m.build_report["samples"] = "300";
  const absl::StatusOr<std::string> text = ModelReportText(m);
  ASSERT_TRUE(text.ok());
  EXPECT_THAT(*text, HasSubstr("500 faces"));
  EXPECT_THAT(*text, HasSubstr("  samples = 300\n"));
}

TEST(ModelReportTest, JsonCarriesTheReportAsAnObject) {
  const std::string json = ModelToJson(Model());
  EXPECT_THAT(json, HasSubstr("\n  \"report\": {\n    \"format\": \"2.1\",\n"));
  EXPECT_THAT(json, HasSubstr("\"name\": \"bob\""));
  EXPECT_EQ(json.substr(json.size() - 6), "  }\n}\n");
}

TEST(ModelReportTest, PercentagesAsTheCoreWritesThem) {
  EXPECT_EQ(FormatPercent(6.42854), "643%");
  EXPECT_EQ(FormatPercent(7.80335e-05), "0.00780%");
  EXPECT_EQ(FormatPercent(1e-9), "<0.001%");
}

}  // namespace
}  // namespace geodex::client::cli
