#include "core/index/report_chart.h"

#include <cairo.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"

namespace geodex::index {
namespace {

using Rgb = std::array<uint8_t, 3>;
// The viewer's colours (client/cli/web/assets/viewer.css, #accuracy-chart).
constexpr Rgb kText = {68, 68, 68};
constexpr Rgb kGrid = {230, 230, 230};
constexpr Rgb kAxis = {153, 153, 153};
constexpr char kFont[] = "DejaVu Sans";
constexpr double kTickSize = 12;
constexpr double kTitleSize = 16;
// The limit's dashes, in pixels on and off.
constexpr double kDash[] = {8, 5};

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* cr) const { cairo_destroy(cr); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using Context = std::unique_ptr<cairo_t, ContextDeleter>;

void SetColor(cairo_t* cr, const Rgb& c) {
  cairo_set_source_rgb(cr, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
}

// Lines are placed so that the pixels the tests look at are covered whole,
// not blended: a line of odd width runs along a row's (column's) centre,
// one of even width along the edge between two rows.
double Centre(int pixel, double width) {
  return static_cast<int>(width) % 2 == 1 ? pixel + 0.5 : pixel;
}

void HLine(cairo_t* cr, int x0, int x1, int y, double width, const Rgb& c, bool dashed = false) {
  SetColor(cr, c);
  cairo_set_line_width(cr, width);
  cairo_set_dash(cr, kDash, dashed ? 2 : 0, 0);
  cairo_move_to(cr, x0, Centre(y, width));
  cairo_line_to(cr, x1 + 1, Centre(y, width));
  cairo_stroke(cr);
}

void VLine(cairo_t* cr, int x, int y0, int y1, double width, const Rgb& c) {
  SetColor(cr, c);
  cairo_set_line_width(cr, width);
  cairo_set_dash(cr, nullptr, 0, 0);
  cairo_move_to(cr, Centre(x, width), std::min(y0, y1));
  cairo_line_to(cr, Centre(x, width), std::max(y0, y1) + 1);
  cairo_stroke(cr);
}

enum class Anchor { kStart, kMiddle, kEnd };

// `text` with its baseline at y, starting, centred or ending at x (as SVG's
// text-anchor). Returns its advance.
double Text(cairo_t* cr, double x, double y, const std::string& text, double size,
            Anchor anchor = Anchor::kStart) {
  cairo_set_font_size(cr, size);
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  if (anchor == Anchor::kMiddle) x -= extents.x_advance / 2;
  if (anchor == Anchor::kEnd) x -= extents.x_advance;
  SetColor(cr, kText);
  cairo_move_to(cr, x, y);
  cairo_show_text(cr, text.c_str());
  return extents.x_advance;
}

double TextWidth(cairo_t* cr, const std::string& text, double size) {
  cairo_set_font_size(cr, size);
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  return extents.x_advance;
}

// A gridline label: the percentage with as many decimals as the step needs.
std::string TickLabel(double fraction, double step) {
  const double percent_step = 100 * step;
  const int decimals =
      percent_step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(percent_step) - 1e-9));
  return absl::StrFormat("%.*f%%", decimals, 100 * fraction);
}

// The chart on a new opaque surface; cairo reports an allocation failure
// in the surface's status.
Surface DrawSurface(const IndexReport& report, int width, int height) {
  assert(width >= 320 && height >= 200);
  Surface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) return surface;
  const Context context(cairo_create(surface.get()));
  cairo_t* cr = context.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, kFont, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);

  const ChartFrame f = MakeChartFrame(report, width, height);
  const ChartLayout layout = MakeChartLayout(report);
  Text(cr, f.left, 26, layout.title, kTitleSize);
  // The gridlines, labelled: errors, then distances.
  for (int k = 0; k * f.error_step <= f.error_max * (1 + 1e-9); ++k) {
    const double e = k * f.error_step;
    HLine(cr, f.left, f.right, f.Y(e), 1, k == 0 ? kAxis : kGrid);
    Text(cr, f.left - 8, f.Y(e) + 4.5, TickLabel(e, f.error_step), kTickSize, Anchor::kEnd);
  }
  for (const ChartTick& tick : layout.ticks) {
    VLine(cr, f.X(tick.at), f.top, f.bottom, 1, tick.at == f.x_min ? kAxis : kGrid);
    // The last label ends at its line, inside the picture.
    Text(cr, f.X(tick.at) + 0.5, f.bottom + 20, tick.label, kTickSize,
         tick.at == f.x_max ? Anchor::kEnd : Anchor::kMiddle);
  }
  Text(cr, (f.left + f.right) / 2.0, f.bottom + 42, layout.axis_label, kTickSize,
       Anchor::kMiddle);
  // The target's p99 limit: a dashed path over the ranges it judges, joined
  // where they meet.
  SetColor(cr, kChartLimitColor);
  cairo_set_line_width(cr, 2);
  cairo_set_dash(cr, kDash, 2, 0);
  for (size_t i = 0; i < layout.limit.size(); ++i) {
    const ChartStep& step = layout.limit[i];
    const double y = Centre(f.Y(step.value), 2);
    if (i > 0 && layout.limit[i - 1].to == step.from) {
      cairo_line_to(cr, f.X(step.from), y);
    } else {
      cairo_move_to(cr, f.X(step.from), y);
    }
    cairo_line_to(cr, f.X(step.to) + 1, y);
  }
  cairo_stroke(cr);
  // The series, the first drawn last (on top): a step over each range, a
  // dot at its geometric middle.
  for (auto series = layout.series.rbegin(); series != layout.series.rend(); ++series) {
    SetColor(cr, series->color);
    for (const ChartStep& step : series->steps) {
      HLine(cr, f.X(step.from), f.X(step.to), f.Y(step.value), 3, series->color);
      cairo_arc(cr, f.X(std::sqrt(step.from * step.to)) + 0.5, f.Y(step.value) + 0.5, 4.5, 0,
                2 * M_PI);
      cairo_fill(cr);
    }
  }
  // The legend, top right, in the viewer's words.
  std::vector<std::pair<std::string, Rgb>> legend;
  for (const ChartSeries& series : layout.series) legend.emplace_back(series.label, series.color);
  legend.emplace_back(absl::StrFormat("limit (target %s)", FormatPercent(report.target_error)),
                      kChartLimitColor);
  double width_needed = 0;
  for (const auto& [label, color] : legend) width_needed += 24 + TextWidth(cr, label, kTickSize);
  double x = f.right - width_needed - 2 * 16;
  for (const auto& [label, color] : legend) {
    const bool dashed = color == kChartLimitColor;
    HLine(cr, static_cast<int>(x), static_cast<int>(x) + 18, 34, dashed ? 2 : 3, color, dashed);
    x += 24 + Text(cr, x + 24, 38.5, label, kTickSize) + 16;
  }
  cairo_surface_flush(surface.get());
  return surface;
}

cairo_status_t AppendToString(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

absl::StatusOr<std::string> SurfacePng(cairo_surface_t* surface) {
  std::string png;
  cairo_status_t status = cairo_surface_status(surface);
  if (status == CAIRO_STATUS_SUCCESS) {
    status = cairo_surface_write_to_png_stream(surface, AppendToString, &png);
  }
  if (status != CAIRO_STATUS_SUCCESS) {
    return absl::InternalError(
        absl::StrFormat("cairo could not encode the chart: %s", cairo_status_to_string(status)));
  }
  return png;
}

// An opaque surface's pixels (cairo keeps 0xAARRGGBB in native-endian words).
ChartImage ImageOf(cairo_surface_t* surface) {
  ChartImage image;
  image.width = cairo_image_surface_get_width(surface);
  image.height = cairo_image_surface_get_height(surface);
  image.rgb.resize(size_t{3} * image.width * image.height);
  const unsigned char* data = cairo_image_surface_get_data(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      uint32_t pixel;
      std::memcpy(&pixel, data + static_cast<size_t>(y) * stride + 4 * x, 4);
      uint8_t* out = &image.rgb[3 * (static_cast<size_t>(y) * image.width + x)];
      out[0] = static_cast<uint8_t>(pixel >> 16);
      out[1] = static_cast<uint8_t>(pixel >> 8);
      out[2] = static_cast<uint8_t>(pixel);
    }
  }
  return image;
}

struct PngReader {
  std::string_view bytes;
  size_t at = 0;
};

cairo_status_t ReadFromView(void* closure, unsigned char* data, unsigned int length) {
  auto* reader = static_cast<PngReader*>(closure);
  if (reader->bytes.size() - reader->at < length) return CAIRO_STATUS_READ_ERROR;
  std::memcpy(data, reader->bytes.data() + reader->at, length);
  reader->at += length;
  return CAIRO_STATUS_SUCCESS;
}

}  // namespace

int ChartFrame::X(double d) const {
  const double t = (std::log10(d) - std::log10(x_min)) / (std::log10(x_max) - std::log10(x_min));
  return left + static_cast<int>(std::lround(t * (right - left)));
}

ChartLayout MakeChartLayout(const IndexReport& report) {
  ChartLayout layout;
  if (report.bands.empty()) {
    // An index of a format before the L1000 bands: its bins by its own L.
    layout.x_min = kChartMinL;
    layout.x_max = kChartMaxL;
    layout.ticks = {{0.1, "0.1L"}, {1, "L"}, {3, "3L"}, {10, "10L"}, {100, "100L"}};
    layout.title = "relative error by distance";
    layout.axis_label = "distance / L (log scale)";
    layout.series = {{"p99", kChartP99Color, {}}, {"RMS", kChartRmsColor, {}}};
    for (const ReportBin& b : report.bins) {
      const double from = std::max(b.from_l, kChartMinL), to = std::min(b.to_l, kChartMaxL);
      if (std::isfinite(b.p99)) layout.series[0].steps.push_back({from, to, b.p99});
      if (std::isfinite(b.rms)) layout.series[1].steps.push_back({from, to, b.rms});
      if (std::isfinite(b.p99_limit)) layout.limit.push_back({from, to, b.p99_limit});
    }
    return layout;
  }
  layout.x_min = kChartMinL1000;
  layout.x_max = kChartMaxL1000;
  layout.ticks = {{0.25, "0.25"}, {1, "1"}, {4, "4"}, {8, "8"}, {16, "16"}, {64, "64"}};
  layout.axis_label = "distance / L1000 (log scale)";
  layout.title = "p99 relative error by distance";
  layout.series = {{"vertex", kChartVertexColor, {}}, {"interior", kChartInteriorColor, {}}};
  for (const ReportBand& b : report.bands) {
    const double from = std::max(b.from, kChartMinL1000), to = std::min(b.to, kChartMaxL1000);
    for (int k = 0; k < 2; ++k) {
      if (std::isfinite(b.p99[k])) layout.series[k].steps.push_back({from, to, b.p99[k]});
    }
    // Only the bands the target judges have a limit.
    if (std::isfinite(b.p99_limit)) layout.limit.push_back({from, to, b.p99_limit});
  }
  return layout;
}

int ChartFrame::Y(double e) const {
  return bottom - static_cast<int>(std::lround(e / error_max * (bottom - top)));
}

double ChartErrorMax(const IndexReport& report, double* step) {
  double top = 0;
  const ChartLayout layout = MakeChartLayout(report);
  for (const ChartSeries& series : layout.series) {
    for (const ChartStep& s : series.steps) top = std::max(top, s.value);
  }
  for (const ChartStep& s : layout.limit) top = std::max(top, s.value);
  top = top > 0 ? 1.1 * top : 0.01;
  // The smallest 1, 2, 5 x 10^k step that needs at most 7 lines.
  const double decade = std::pow(10.0, std::floor(std::log10(top / 7)));
  double s = decade;
  for (const double f : {1.0, 2.0, 5.0, 10.0}) {
    s = f * decade;
    if (top / s <= 7) break;
  }
  *step = s;
  return std::ceil(top / s - 1e-9) * s;
}

ChartFrame MakeChartFrame(const IndexReport& report, int width, int height) {
  ChartFrame f;
  f.left = 70;
  f.right = width - 24;
  f.top = 48;
  f.bottom = height - 52;
  f.error_max = ChartErrorMax(report, &f.error_step);
  const ChartLayout layout = MakeChartLayout(report);
  f.x_min = layout.x_min;
  f.x_max = layout.x_max;
  return f;
}

ChartImage DrawReportChart(const IndexReport& report, int width, int height) {
  const Surface surface = DrawSurface(report, width, height);
  // A surface of a few hundred pixels a side fails only when memory does.
  assert(cairo_surface_status(surface.get()) == CAIRO_STATUS_SUCCESS);
  return ImageOf(surface.get());
}

absl::StatusOr<std::string> EncodeChartPng(const ChartImage& image) {
  assert(image.width > 0 && image.height > 0);
  assert(image.rgb.size() == size_t{3} * image.width * image.height);
  const Surface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, image.width, image.height));
  if (cairo_surface_status(surface.get()) == CAIRO_STATUS_SUCCESS) {
    cairo_surface_flush(surface.get());
    unsigned char* data = cairo_image_surface_get_data(surface.get());
    const int stride = cairo_image_surface_get_stride(surface.get());
    for (int y = 0; y < image.height; ++y) {
      for (int x = 0; x < image.width; ++x) {
        const auto [r, g, b] = image.At(x, y);
        const uint32_t pixel = 0xff000000u | uint32_t{r} << 16 | uint32_t{g} << 8 | b;
        std::memcpy(data + static_cast<size_t>(y) * stride + 4 * x, &pixel, 4);
      }
    }
    cairo_surface_mark_dirty(surface.get());
  }
  return SurfacePng(surface.get());
}

absl::StatusOr<ChartImage> DecodeChartPng(std::string_view png) {
  PngReader reader{png};
  const Surface surface(cairo_image_surface_create_from_png_stream(ReadFromView, &reader));
  const cairo_status_t status = cairo_surface_status(surface.get());
  if (status != CAIRO_STATUS_SUCCESS) {
    return absl::InvalidArgumentError(
        absl::StrFormat("not a PNG cairo reads: %s", cairo_status_to_string(status)));
  }
  return ImageOf(surface.get());
}

absl::Status WriteReportPng(const IndexReport& report, const std::string& path) {
  if (!report.has_accuracy) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "%s: the index has no accuracy calibration to draw (geodex-build calibrate adds it)",
        path));
  }
  const Surface surface = DrawSurface(report, 720, 420);
  GEODEX_ASSIGN_OR_RETURN(const std::string png, SurfacePng(surface.get()));
  return AtomicWriteFile(path, png);
}

}  // namespace geodex::index
