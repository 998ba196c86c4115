#include "core/index/report_chart.h"

#include <zlib.h>

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cmath>
#include <map>

#include "absl/strings/str_format.h"
#include "core/common/file_util.h"

namespace geodex::index {
namespace {

using Rgb = std::array<uint8_t, 3>;
constexpr Rgb kText = {40, 40, 40};
constexpr Rgb kGrid = {225, 225, 225};
constexpr Rgb kAxis = {150, 150, 150};

// A 5 x 7 bitmap font, upper case: each row's five bits, the leftmost the
// highest. Lower-case text is drawn in capitals.
const std::map<char, std::array<uint8_t, 7>>& Font() {
  static const auto* const font = new std::map<char, std::array<uint8_t, 7>>{
      {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
      {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
      {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
      {',', {0x00, 0x00, 0x00, 0x00, 0x0c, 0x04, 0x08}},
      {'-', {0x00, 0x00, 0x00, 0x1f, 0x00, 0x00, 0x00}},
      {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0c, 0x0c}},
      {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
      {'0', {0x0e, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0e}},
      {'1', {0x04, 0x0c, 0x04, 0x04, 0x04, 0x04, 0x0e}},
      {'2', {0x0e, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1f}},
      {'3', {0x1f, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0e}},
      {'4', {0x02, 0x06, 0x0a, 0x12, 0x1f, 0x02, 0x02}},
      {'5', {0x1f, 0x10, 0x1e, 0x01, 0x01, 0x11, 0x0e}},
      {'6', {0x06, 0x08, 0x10, 0x1e, 0x11, 0x11, 0x0e}},
      {'7', {0x1f, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
      {'8', {0x0e, 0x11, 0x11, 0x0e, 0x11, 0x11, 0x0e}},
      {'9', {0x0e, 0x11, 0x11, 0x0f, 0x01, 0x02, 0x0c}},
      {':', {0x00, 0x0c, 0x0c, 0x00, 0x0c, 0x0c, 0x00}},
      {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
      {'=', {0x00, 0x00, 0x1f, 0x00, 0x1f, 0x00, 0x00}},
      {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
      {'A', {0x0e, 0x11, 0x11, 0x1f, 0x11, 0x11, 0x11}},
      {'B', {0x1e, 0x11, 0x11, 0x1e, 0x11, 0x11, 0x1e}},
      {'C', {0x0e, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0e}},
      {'D', {0x1e, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1e}},
      {'E', {0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x1f}},
      {'F', {0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x10}},
      {'G', {0x0e, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0f}},
      {'H', {0x11, 0x11, 0x11, 0x1f, 0x11, 0x11, 0x11}},
      {'I', {0x0e, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0e}},
      {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0c}},
      {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
      {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1f}},
      {'M', {0x11, 0x1b, 0x15, 0x15, 0x11, 0x11, 0x11}},
      {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
      {'O', {0x0e, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e}},
      {'P', {0x1e, 0x11, 0x11, 0x1e, 0x10, 0x10, 0x10}},
      {'Q', {0x0e, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0d}},
      {'R', {0x1e, 0x11, 0x11, 0x1e, 0x14, 0x12, 0x11}},
      {'S', {0x0f, 0x10, 0x10, 0x0e, 0x01, 0x01, 0x1e}},
      {'T', {0x1f, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
      {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e}},
      {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0a, 0x04}},
      {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0a}},
      {'X', {0x11, 0x11, 0x0a, 0x04, 0x0a, 0x11, 0x11}},
      {'Y', {0x11, 0x11, 0x0a, 0x04, 0x04, 0x04, 0x04}},
      {'Z', {0x1f, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1f}},
  };
  return *font;
}

class Canvas {
 public:
  Canvas(int width, int height) : image_{width, height, {}} {
    image_.rgb.resize(size_t{3} * width * height, 255);
  }
  ChartImage Take() { return std::move(image_); }

  void Set(int x, int y, const Rgb& c) {
    if (x < 0 || y < 0 || x >= image_.width || y >= image_.height) return;
    const size_t i = 3 * (static_cast<size_t>(y) * image_.width + x);
    std::copy(c.begin(), c.end(), image_.rgb.begin() + i);
  }
  void Rect(int x0, int y0, int x1, int y1, const Rgb& c) {
    for (int y = std::min(y0, y1); y <= std::max(y0, y1); ++y) {
      for (int x = std::min(x0, x1); x <= std::max(x0, x1); ++x) Set(x, y, c);
    }
  }
  // A horizontal line `thickness` pixels thick centred on row y; `dash` > 0
  // draws dash pixels on, dash off.
  void HLine(int x0, int x1, int y, int thickness, const Rgb& c, int dash = 0) {
    for (int x = std::min(x0, x1); x <= std::max(x0, x1); ++x) {
      if (dash > 0 && ((x - x0) / dash) % 2 == 1) continue;
      for (int t = 0; t < thickness; ++t) Set(x, y - thickness / 2 + t, c);
    }
  }
  void VLine(int x, int y0, int y1, int thickness, const Rgb& c, int dash = 0) {
    for (int y = std::min(y0, y1); y <= std::max(y0, y1); ++y) {
      if (dash > 0 && ((y - y0) / dash) % 2 == 1) continue;
      for (int t = 0; t < thickness; ++t) Set(x - thickness / 2 + t, y, c);
    }
  }
  void Dot(int cx, int cy, int r, const Rgb& c) {
    for (int y = -r; y <= r; ++y) {
      for (int x = -r; x <= r; ++x) {
        if (x * x + y * y <= r * r) Set(cx + x, cy + y, c);
      }
    }
  }
  static int TextWidth(const std::string& text, int scale) {
    return static_cast<int>(text.size()) * 6 * scale - scale;
  }
  // `text` with its top-left corner at (x, y).
  void Text(int x, int y, const std::string& text, int scale, const Rgb& c) {
    for (const char ch : text) {
      const auto glyph =
          Font().find(static_cast<char>(std::toupper(static_cast<unsigned char>(ch))));
      if (glyph != Font().end()) {
        for (int row = 0; row < 7; ++row) {
          for (int col = 0; col < 5; ++col) {
            if ((glyph->second[row] >> (4 - col)) & 1) {
              Rect(x + col * scale, y + row * scale, x + col * scale + scale - 1,
                   y + row * scale + scale - 1, c);
            }
          }
        }
      }
      x += 6 * scale;
    }
  }

 private:
  ChartImage image_;
};

void AppendBigEndian32(uint32_t v, std::string* out) {
  for (int shift = 24; shift >= 0; shift -= 8) out->push_back(static_cast<char>(v >> shift));
}

void AppendChunk(const char* type, const std::string& data, std::string* png) {
  AppendBigEndian32(static_cast<uint32_t>(data.size()), png);
  const std::string body = std::string(type, 4) + data;
  *png += body;
  AppendBigEndian32(
      static_cast<uint32_t>(crc32(crc32(0, nullptr, 0), reinterpret_cast<const Bytef*>(body.data()),
                                  static_cast<uInt>(body.size()))),
      png);
}

// A gridline label: the percentage with as many decimals as the step needs.
std::string TickLabel(double fraction, double step) {
  const double percent_step = 100 * step;
  const int decimals =
      percent_step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(percent_step) - 1e-9));
  return absl::StrFormat("%.*f%%", decimals, 100 * fraction);
}

}  // namespace

int ChartFrame::X(double l) const {
  const double t =
      (std::log10(l) - std::log10(kChartMinL)) / (std::log10(kChartMaxL) - std::log10(kChartMinL));
  return left + static_cast<int>(std::lround(t * (right - left)));
}

int ChartFrame::Y(double e) const {
  return bottom - static_cast<int>(std::lround(e / error_max * (bottom - top)));
}

double ChartErrorMax(const IndexReport& report, double* step) {
  double top = 0;
  for (const ReportBin& b : report.bins) {
    for (const double v : {b.p99, b.rms, b.p99_limit}) {
      if (std::isfinite(v)) top = std::max(top, v);
    }
  }
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
  return f;
}

ChartImage DrawReportChart(const IndexReport& report, int width, int height) {
  assert(width >= 320 && height >= 200);
  const ChartFrame f = MakeChartFrame(report, width, height);
  Canvas c(width, height);
  c.Text(f.left, 12, "relative error by distance", 2, kText);
  // The gridlines, labelled: errors, then distances (decades and 3L, the
  // edge between the target's two limits).
  for (int k = 0; k * f.error_step <= f.error_max * (1 + 1e-9); ++k) {
    const double e = k * f.error_step;
    c.HLine(f.left, f.right, f.Y(e), 1, k == 0 ? kAxis : kGrid);
    const std::string label = TickLabel(e, f.error_step);
    c.Text(f.left - 8 - Canvas::TextWidth(label, 1), f.Y(e) - 3, label, 1, kText);
  }
  const std::pair<double, const char*> ticks[] = {
      {0.1, "0.1L"}, {1, "L"}, {3, "3L"}, {10, "10L"}, {100, "100L"}};
  for (const auto& [l, label] : ticks) {
    c.VLine(f.X(l), f.top, f.bottom, 1, l == kChartMinL ? kAxis : kGrid);
    c.Text(f.X(l) - Canvas::TextWidth(label, 1) / 2, f.bottom + 8, label, 1, kText);
  }
  const std::string axis = "distance / L (log scale)";
  c.Text((f.left + f.right - Canvas::TextWidth(axis, 1)) / 2, f.bottom + 28, axis, 1, kText);
  // The target's p99 limit: dashed, a step at 3L.
  for (const ReportBin& b : report.bins) {
    const double from = std::max(b.from_l, kChartMinL), to = std::min(b.to_l, kChartMaxL);
    c.HLine(f.X(from), f.X(to), f.Y(b.p99_limit), 2, kChartLimitColor, 6);
  }
  c.VLine(f.X(3), f.Y(report.bins[1].p99_limit), f.Y(report.bins[2].p99_limit), 2, kChartLimitColor,
          6);
  // The series: RMS under p99; a step over each bin, a dot at its middle.
  for (const auto& [rms, color] :
       {std::make_pair(true, kChartRmsColor), std::make_pair(false, kChartP99Color)}) {
    for (const ReportBin& b : report.bins) {
      const double v = rms ? b.rms : b.p99;
      if (!std::isfinite(v)) continue;
      const double from = std::max(b.from_l, kChartMinL), to = std::min(b.to_l, kChartMaxL);
      c.HLine(f.X(from), f.X(to), f.Y(v), 3, color);
      c.Dot(f.X(std::sqrt(from * to)), f.Y(v), 4, color);
    }
  }
  // The legend, top right.
  const std::string limit =
      absl::StrFormat("%s limit (target %s)", "p99", FormatPercent(report.target_error));
  int x = f.right - Canvas::TextWidth("p99", 1) - Canvas::TextWidth("RMS", 1) -
          Canvas::TextWidth(limit, 1) - 3 * 30;
  const std::pair<std::string, Rgb> legend[] = {
      {"p99", kChartP99Color}, {"RMS", kChartRmsColor}, {limit, kChartLimitColor}};
  for (const auto& [label, color] : legend) {
    if (color == kChartLimitColor) {
      c.HLine(x, x + 18, 40, 2, color, 6);
    } else {
      c.HLine(x, x + 18, 40, 3, color);
    }
    c.Text(x + 24, 37, label, 1, kText);
    x += 30 + Canvas::TextWidth(label, 1);
  }
  return c.Take();
}

std::string EncodeChartPng(const ChartImage& image) {
  const size_t row_bytes = size_t{3} * image.width;
  std::string rows;
  rows.reserve((row_bytes + 1) * image.height);
  for (int y = 0; y < image.height; ++y) {
    rows.push_back('\0');  // filter type 0: flat colours compress well unfiltered
    rows.append(reinterpret_cast<const char*>(image.rgb.data()) + y * row_bytes, row_bytes);
  }
  uLongf size = compressBound(static_cast<uLong>(rows.size()));
  std::string compressed(size, '\0');
  const int status = compress2(reinterpret_cast<Bytef*>(compressed.data()), &size,
                               reinterpret_cast<const Bytef*>(rows.data()),
                               static_cast<uLong>(rows.size()), Z_BEST_COMPRESSION);
  // compressBound rules out Z_BUF_ERROR; Z_MEM_ERROR is out of memory.
  assert(status == Z_OK);
  (void)status;
  compressed.resize(size);
  std::string png = "\x89PNG\r\n\x1a\n";
  std::string header;
  AppendBigEndian32(static_cast<uint32_t>(image.width), &header);
  AppendBigEndian32(static_cast<uint32_t>(image.height), &header);
  header.append({'\x08', '\x02', '\x00', '\x00', '\x00'});  // 8-bit RGB, no interlace
  AppendChunk("IHDR", header, &png);
  AppendChunk("IDAT", compressed, &png);
  AppendChunk("IEND", "", &png);
  return png;
}

absl::Status WriteReportPng(const IndexReport& report, const std::string& path) {
  if (!report.has_accuracy) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "%s: the index has no accuracy calibration to draw (geodex-build calibrate adds it)",
        path));
  }
  return AtomicWriteFile(path, EncodeChartPng(DrawReportChart(report)));
}

}  // namespace geodex::index
