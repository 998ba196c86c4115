#pragma once

// The picture of a build report's accuracy: the calibration's p99 relative
// error against distance, as a PNG (geodex-build --report-png).
//
// Distance runs along a logarithmic axis in L1000 (the spacing of 1,000
// samples on the surface, the unit of the report's bands), from 0.25 to 64;
// each band (0-0.5, ..., >= 16) is a horizontal step over its range (the
// first from 0.25, the last to 64) with a dot at its geometric middle, one
// series for vertex pairs and one for interior pairs; relative error runs up
// a linear axis in %. The target's p99 limit is dashed over the bands it
// judges, and only there. An index of a format before the bands is drawn by
// its own bins in its own L (p99 and RMS, 0.1L to 100L). The viewer draws the
// same chart (client/cli/web/assets/report_chart.js) from the report's JSON,
// with the same layout. Drawn with cairo: anti-aliased lines and DejaVu Sans
// (any sans-serif fontconfig finds when it is absent).
//
//   const IndexReport report = MakeIndexReport(index);
//   absl::Status written = WriteReportPng(report, "report.png");
//
// Thread-safe: pure functions of their arguments (WriteReportPng writes its
// file); each call draws on a cairo surface of its own.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/index/index_report.h"

namespace geodex::index {

// The chart's distance axis, log scale: [kChartMinL1000, kChartMaxL1000] in
// L1000, or [kChartMinL, kChartMaxL] in the index's L for a report without
// bands.
inline constexpr double kChartMinL1000 = 0.25;
inline constexpr double kChartMaxL1000 = 64;
inline constexpr double kChartMinL = 0.1;
inline constexpr double kChartMaxL = 100;

// The series' colours, for tests that look for them: a report with bands
// draws vertex pairs in the first and interior pairs in the second; one
// without, p99 and RMS.
inline constexpr std::array<uint8_t, 3> kChartP99Color = {214, 39, 40};
inline constexpr std::array<uint8_t, 3> kChartRmsColor = {31, 119, 180};
inline constexpr std::array<uint8_t, 3> kChartVertexColor = kChartP99Color;
inline constexpr std::array<uint8_t, 3> kChartInteriorColor = kChartRmsColor;
inline constexpr std::array<uint8_t, 3> kChartLimitColor = {90, 90, 90};

// What the chart draws, whatever the picture's size: the distance axis, its
// ticks, and each series and the target's limit as steps over distance
// ranges (the axis's unit), values being relative errors.
struct ChartStep {
  double from = 0, to = 0;  // clipped to the axis
  double value = 0;
};
struct ChartTick {
  double at = 0;
  std::string label;
};
struct ChartSeries {
  std::string label;
  std::array<uint8_t, 3> color;
  std::vector<ChartStep> steps;  // figures that are not finite are left out
};
struct ChartLayout {
  std::string title;
  double x_min = 0, x_max = 0;
  std::vector<ChartTick> ticks;
  std::string axis_label;
  std::vector<ChartSeries> series;
  std::vector<ChartStep> limit;  // the judged ranges only
};
ChartLayout MakeChartLayout(const IndexReport& report);

// Where the chart's plot lies in an image of width x height pixels, and
// the error at its top.
struct ChartFrame {
  int left = 0, top = 0, right = 0, bottom = 0;  // the plot's pixels, inclusive
  double error_max = 0;                          // relative error at the top
  double error_step = 0;                         // between gridlines
  double x_min = 0, x_max = 0;                   // the distance axis (ChartLayout's)
  // The pixel column of distance `d` (in the axis's unit) and the row of
  // relative error `e`, rounded to the nearest pixel.
  int X(double d) const;
  int Y(double e) const;
};

// The top of the error axis: the largest figure drawn (series, limit)
// times 1.1, rounded up to a whole number of gridline steps, the step being
// 1, 2 or 5 times a power of ten giving 3 to 7 lines. `step` receives the
// step. Figures that are not finite are ignored; all zero gives 1%.
double ChartErrorMax(const IndexReport& report, double* step);

ChartFrame MakeChartFrame(const IndexReport& report, int width, int height);

// An 8-bit RGB image; pixel (x, y), y = 0 the top row, is the three bytes at
// rgb[3 * (y * width + x)]. Lines and dots are anti-aliased: a pixel on a
// figure's edge blends its colour with what lies under it, a pixel inside
// (the middle row of a series' step, the centre of its dot) has it exactly.
struct ChartImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;
  std::array<uint8_t, 3> At(int x, int y) const {
    const size_t i = 3 * (static_cast<size_t>(y) * width + x);
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

// The chart of `report` (which must have its accuracy: has_accuracy).
// width >= 320 and height >= 200.
ChartImage DrawReportChart(const IndexReport& report, int width = 720, int height = 420);

// `image` as PNG bytes (8-bit RGB, cairo's encoder). Errors: Internal when
// cairo fails (out of memory).
absl::StatusOr<std::string> EncodeChartPng(const ChartImage& image);

// The pixels of PNG bytes (any PNG cairo reads; alpha dropped). Errors:
// InvalidArgument for bytes that are not a PNG cairo can read.
absl::StatusOr<ChartImage> DecodeChartPng(std::string_view png);

// Draws the chart and writes it atomically to `path`. Errors:
// FailedPrecondition for a report without a calibration (nothing to draw);
// the file errors of core/common/file_util.h.
absl::Status WriteReportPng(const IndexReport& report, const std::string& path);

}  // namespace geodex::index
