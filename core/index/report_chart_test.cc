#include "core/index/report_chart.h"

#include <cmath>
#include <set>
#include <string>

#include "gtest/gtest.h"

namespace geodex::index {
namespace {

IndexReport Report() {
  IndexReport r;
  r.has_accuracy = true;
  r.target_error = 0.005;
  const double rms[4] = {0.0015, 0.0058, 0.015, 0.018};
  const double p99[4] = {7.8e-5, 0.03, 0.055, 0.047};
  const double edges[5] = {0, 1, 3, 10, INFINITY};
  for (int b = 0; b < 4; ++b) {
    r.bins[b].from_l = edges[b];
    r.bins[b].to_l = edges[b + 1];
    r.bins[b].rms = rms[b];
    r.bins[b].p99 = p99[b];
    r.bins[b].p99_limit = (b < 2 ? 2 : 4) * r.target_error;
  }
  return r;
}

TEST(ReportChartTest, ErrorAxisEndsAboveTheLargestFigureOnAWholeStep) {
  double step = 0;
  const double top = ChartErrorMax(Report(), &step);
  EXPECT_DOUBLE_EQ(step, 0.01);  // 1.1 x 5.5% = 6.05%: 7 lines of 1%
  EXPECT_DOUBLE_EQ(top, 0.07);
  IndexReport huge = Report();
  huge.bins[0].p99 = 6.42854;  // 643%: the axis follows
  EXPECT_GE(ChartErrorMax(huge, &step), 1.1 * 6.42854);
  EXPECT_LE(ChartErrorMax(huge, &step) / step, 7 + 1e-9);
}

// Each bin's figures are drawn where the frame puts them: the chart's
// values are the report's.
TEST(ReportChartTest, DrawsEachBinsFiguresAndTheTargetWhereTheFramePutsThem) {
  const IndexReport r = Report();
  const ChartImage image = DrawReportChart(r, 720, 420);
  const ChartFrame f = MakeChartFrame(r, 720, 420);
  ASSERT_EQ(image.rgb.size(), 3u * 720 * 420);
  const double mids[4] = {std::sqrt(0.1 * 1), std::sqrt(3.0), std::sqrt(30.0), std::sqrt(1000.0)};
  for (int b = 0; b < 4; ++b) {
    EXPECT_EQ(image.At(f.X(mids[b]), f.Y(r.bins[b].p99)), kChartP99Color) << b;
    if (std::abs(f.Y(r.bins[b].p99) - f.Y(r.bins[b].rms)) > 6) {
      EXPECT_EQ(image.At(f.X(mids[b]), f.Y(r.bins[b].rms)), kChartRmsColor) << b;
    }
  }
  // The limit, dashed: some pixel of its row over L-3L has its colour.
  int limit_pixels = 0;
  for (int x = f.X(1.2); x < f.X(2.8); ++x)
    limit_pixels += image.At(x, f.Y(0.01)) == kChartLimitColor;
  EXPECT_GT(limit_pixels, 10);
  // Nothing of the p99 series where the 3L-10L bin has no figure.
  EXPECT_NE(image.At(f.X(mids[2]), f.Y(0.03)), kChartP99Color);
}

// A report of today's format: p99 by L1000 band, vertex and interior pairs,
// the limit on the bands from 8 L1000 only.
IndexReport BandsReport() {
  IndexReport r = Report();
  const double edges[8] = {0, 0.5, 1, 2, 4, 8, 16, INFINITY};
  const double vertex[7] = {0, 0.0001, 0.002, 0.045, 0.03, 0.015, 0.012};
  const double interior[7] = {0, 0, 0.001, 0.02, 0.025, 0.014, NAN};
  for (int b = 0; b < 7; ++b) {
    ReportBand band;
    band.from = edges[b];
    band.to = edges[b + 1];
    band.p99[0] = vertex[b];
    band.p99[1] = interior[b];
    band.p99_limit = b >= 5 ? 4 * r.target_error : NAN;
    r.bands.push_back(band);
  }
  return r;
}

TEST(ReportChartTest, BandsAreDrawnInL1000WithTheLimitOnlyWhereTheTargetJudges) {
  const IndexReport r = BandsReport();
  const ChartLayout layout = MakeChartLayout(r);
  EXPECT_EQ(layout.x_min, kChartMinL1000);
  EXPECT_EQ(layout.axis_label, "distance / L1000 (log scale)");
  ASSERT_EQ(layout.series.size(), 2u);
  EXPECT_EQ(layout.series[0].steps.size(), 7u);
  EXPECT_EQ(layout.series[1].steps.size(), 6u);  // the last band's NaN is left out
  ASSERT_EQ(layout.limit.size(), 2u);
  EXPECT_EQ(layout.limit[0].from, 8);
  EXPECT_EQ(layout.limit[1].to, kChartMaxL1000);
  double step = 0;
  EXPECT_DOUBLE_EQ(ChartErrorMax(r, &step), 0.05);  // 1.1 x 4.5% = 4.95%: 5 lines of 1%

  const ChartImage image = DrawReportChart(r, 720, 420);
  const ChartFrame f = MakeChartFrame(r, 720, 420);
  for (int b = 2; b < 5; ++b) {
    const double mid = std::sqrt(r.bands[b].from * r.bands[b].to);
    EXPECT_EQ(image.At(f.X(mid), f.Y(r.bands[b].p99[0])), kChartVertexColor) << b;
    if (std::abs(f.Y(r.bands[b].p99[0]) - f.Y(r.bands[b].p99[1])) > 6) {
      EXPECT_EQ(image.At(f.X(mid), f.Y(r.bands[b].p99[1])), kChartInteriorColor) << b;
    }
  }
  // The limit's row: dashed over 8-64, and nothing of it over 1-4.
  int judged = 0, unjudged = 0;
  for (int x = f.X(9); x < f.X(60); ++x) judged += image.At(x, f.Y(0.02)) == kChartLimitColor;
  for (int x = f.X(1.1); x < f.X(3.9); ++x) unjudged += image.At(x, f.Y(0.02)) == kChartLimitColor;
  EXPECT_GT(judged, 30);
  EXPECT_EQ(unjudged, 0);
}

// The PNG is 8-bit RGB of the chart's size, and reads back to the same
// pixels: nothing is lost on the way to the file.
TEST(ReportChartTest, PngHoldsTheImage) {
  const ChartImage image = DrawReportChart(Report(), 400, 250);
  const absl::StatusOr<std::string> png = EncodeChartPng(image);
  ASSERT_TRUE(png.ok()) << png.status();
  ASSERT_EQ(png->substr(0, 8), "\x89PNG\r\n\x1a\n");
  EXPECT_EQ(png->substr(12, 4), "IHDR");
  EXPECT_EQ(png->substr(16, 8), std::string("\0\0\x01\x90\0\0\0\xfa", 8));  // 400 x 250
  EXPECT_EQ(png->substr(24, 2), std::string("\x08\x02", 2));                // 8 bits, RGB
  const absl::StatusOr<ChartImage> back = DecodeChartPng(*png);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->width, 400);
  EXPECT_EQ(back->height, 250);
  EXPECT_EQ(back->rgb, image.rgb);
}

TEST(ReportChartTest, DecodingRefusesWhatIsNotAPng) {
  EXPECT_EQ(DecodeChartPng("GIF89a").status().code(), absl::StatusCode::kInvalidArgument);
  const std::string png = *EncodeChartPng(DrawReportChart(Report(), 400, 250));
  EXPECT_EQ(DecodeChartPng(png.substr(0, png.size() / 2)).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// The chart has text: tick labels left of the plot and a title above it,
// drawn in the text's colour blended by anti-aliasing (so: grey levels
// between the text's and white, and more than one of them).
TEST(ReportChartTest, LabelsAreDrawnAntiAliased) {
  const IndexReport r = Report();
  const ChartImage image = DrawReportChart(r, 720, 420);
  const ChartFrame f = MakeChartFrame(r, 720, 420);
  std::set<int> greys;
  for (int y = f.top - 10; y <= f.bottom + 10; ++y) {
    for (int x = 0; x < f.left - 6; ++x) {
      const auto [red, green, blue] = image.At(x, y);
      if (red == green && green == blue && red < 255) greys.insert(red);
    }
  }
  EXPECT_GT(greys.size(), 5u);
  EXPECT_EQ(*greys.begin() <= 100, true);  // the text's own colour, dark
}

TEST(ReportChartTest, RefusesAReportWithoutCalibration) {
  IndexReport r;
  EXPECT_EQ(WriteReportPng(r, "/nonexistent/x.png").code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace geodex::index
