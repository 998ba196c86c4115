#include "core/index/report_chart.h"

#include <zlib.h>

#include <cmath>
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

uint32_t BigEndian32(const std::string& s, size_t at) {
  uint32_t v = 0;
  for (int k = 0; k < 4; ++k) v = v << 8 | static_cast<uint8_t>(s[at + k]);
  return v;
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

TEST(ReportChartTest, PngHoldsTheImage) {
  const ChartImage image = DrawReportChart(Report(), 400, 250);
  const std::string png = EncodeChartPng(image);
  ASSERT_EQ(png.substr(0, 8), "\x89PNG\r\n\x1a\n");
  EXPECT_EQ(png.substr(12, 4), "IHDR");
  EXPECT_EQ(BigEndian32(png, 16), 400u);
  EXPECT_EQ(BigEndian32(png, 20), 250u);
  const size_t idat = 8 + 12 + 13;
  ASSERT_EQ(png.substr(idat + 4, 4), "IDAT");
  const uint32_t length = BigEndian32(png, idat);
  std::string rows(size_t{250} * (3 * 400 + 1), '\0');
  uLongf size = rows.size();
  ASSERT_EQ(uncompress(reinterpret_cast<Bytef*>(rows.data()), &size,
                       reinterpret_cast<const Bytef*>(png.data() + idat + 8), length),
            Z_OK);
  ASSERT_EQ(size, rows.size());
  for (int y = 0; y < 250; ++y) {
    ASSERT_EQ(rows[y * (3 * 400 + 1)], '\0');
    ASSERT_EQ(rows.compare(y * (3 * 400 + 1) + 1, 3 * 400,
                           reinterpret_cast<const char*>(image.rgb.data()) + y * 3 * 400, 3 * 400),
              0);
  }
  const uint32_t crc = crc32(crc32(0, nullptr, 0),
                             reinterpret_cast<const Bytef*>(png.data() + idat + 4), length + 4);
  EXPECT_EQ(BigEndian32(png, idat + 8 + length), crc);
  EXPECT_EQ(png.substr(png.size() - 8, 4), "IEND");
}

TEST(ReportChartTest, RefusesAReportWithoutCalibration) {
  IndexReport r;
  EXPECT_EQ(WriteReportPng(r, "/nonexistent/x.png").code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace geodex::index
