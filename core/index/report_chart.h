#pragma once

// The picture of a build report's accuracy: the calibration's p99 and RMS
// relative error against distance, as a PNG (geodex-build --report-png).
//
// Distance runs along a logarithmic axis in units of the sample spacing L,
// from 0.1L to 100L; each of the report's bins (d < L, L-3L, 3L-10L,
// >= 10L) is a horizontal step over its range (d < L from 0.1L, >= 10L to
// 100L) with a dot at its geometric middle; relative error runs up a linear
// axis in %. The error target's p99 limit (2E below 3L, 4E from 3L) is the
// dashed line. The viewer draws the same chart (client/cli/web/assets/
// report_chart.js) from the report's JSON, with the same frame. Drawn with
// cairo: anti-aliased lines and DejaVu Sans (any sans-serif fontconfig
// finds when it is absent).
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

// The chart's axes: distance / L in [kChartMinL, kChartMaxL], log scale.
inline constexpr double kChartMinL = 0.1;
inline constexpr double kChartMaxL = 100;

// Where the chart's plot lies in an image of width x height pixels, and
// the error at its top.
struct ChartFrame {
  int left = 0, top = 0, right = 0, bottom = 0;  // the plot's pixels, inclusive
  double error_max = 0;                          // relative error at the top
  double error_step = 0;                         // between gridlines
  // The pixel column of distance `l` (in units of L) and the row of relative
  // error `e`, rounded to the nearest pixel.
  int X(double l) const;
  int Y(double e) const;
};

// The top of the error axis: the largest figure drawn (p99, RMS, limit)
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

// The series' colours, for tests that look for them.
inline constexpr std::array<uint8_t, 3> kChartP99Color = {214, 39, 40};
inline constexpr std::array<uint8_t, 3> kChartRmsColor = {31, 119, 180};
inline constexpr std::array<uint8_t, 3> kChartLimitColor = {90, 90, 90};

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
