#include "client/cli/image.h"

#include <zlib.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string_view>

namespace geodex::client::cli {
namespace {

// Dark and light square colours of the plain squares and of the two marks.
// The marks keep the plain squares' brightness contrast so the pattern stays
// readable inside them.
constexpr Rgb kPlainDark = {45, 50, 60};
constexpr Rgb kPlainLight = {235, 235, 230};
constexpr Rgb kQuadrantDark = {150, 30, 35};
constexpr Rgb kQuadrantLight = {250, 185, 180};
constexpr Rgb kAxisDark = {25, 115, 45};
constexpr Rgb kAxisLight = {185, 240, 180};

// Decoders accept IDAT split anywhere; bounded chunks keep each one far from
// the format's 2^31 - 1 byte limit and let streaming readers work in pieces.
constexpr size_t kMaxIdatChunkBytes = size_t{1} << 20;

void AppendBigEndian32(uint32_t value, std::string* out) {
  out->push_back(static_cast<char>(value >> 24));
  out->push_back(static_cast<char>(value >> 16));
  out->push_back(static_cast<char>(value >> 8));
  out->push_back(static_cast<char>(value));
}

void AppendChunk(std::string_view type, std::string_view data, std::string* out) {
  AppendBigEndian32(static_cast<uint32_t>(data.size()), out);
  const size_t typed_start = out->size();
  out->append(type);
  out->append(data);
  // The CRC covers the chunk type and data, not the length.
  const uLong crc =
      crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(out->data() + typed_start),
            static_cast<uInt>(out->size() - typed_start));
  AppendBigEndian32(static_cast<uint32_t>(crc), out);
}

int SquareIndex(double coordinate, int squares) {
  const double scaled = std::floor(coordinate * squares);
  return static_cast<int>(std::clamp(scaled, 0.0, static_cast<double>(squares - 1)));
}

}  // namespace

std::string EncodePng(const Image& image) {
  const bool well_formed = image.width > 0 && image.height > 0 &&
                           image.rgb.size() == size_t{3} * static_cast<size_t>(image.width) *
                                                   static_cast<size_t>(image.height);
  assert(well_formed);
  if (!well_formed) return "";

  const size_t row_bytes = size_t{3} * static_cast<size_t>(image.width);
  // Every scanline gets filter type 0 (none): the flat-coloured images these
  // are compress well without prediction, and the data stays easy to check.
  std::string scanlines;
  scanlines.reserve((row_bytes + 1) * static_cast<size_t>(image.height));
  for (int y = 0; y < image.height; ++y) {
    scanlines.push_back('\0');
    scanlines.append(reinterpret_cast<const char*>(image.rgb.data()) + y * row_bytes, row_bytes);
  }
  uLongf compressed_size = compressBound(static_cast<uLong>(scanlines.size()));
  std::string compressed(compressed_size, '\0');
  const int zlib_status = compress2(reinterpret_cast<Bytef*>(compressed.data()), &compressed_size,
                                    reinterpret_cast<const Bytef*>(scanlines.data()),
                                    static_cast<uLong>(scanlines.size()), Z_DEFAULT_COMPRESSION);
  // compressBound makes Z_BUF_ERROR impossible; Z_MEM_ERROR is out of memory.
  assert(zlib_status == Z_OK);
  if (zlib_status != Z_OK) return "";
  compressed.resize(compressed_size);

  std::string png = "\x89PNG\r\n\x1a\n";
  std::string header;
  AppendBigEndian32(static_cast<uint32_t>(image.width), &header);
  AppendBigEndian32(static_cast<uint32_t>(image.height), &header);
  // Bit depth 8, colour type 2 (RGB), deflate, adaptive filtering, no interlace.
  header.append({'\x08', '\x02', '\x00', '\x00', '\x00'});
  AppendChunk("IHDR", header, &png);
  const std::string_view idat = compressed;
  for (size_t offset = 0; offset < idat.size(); offset += kMaxIdatChunkBytes) {
    AppendChunk("IDAT", idat.substr(offset, kMaxIdatChunkBytes), &png);
  }
  AppendChunk("IEND", "", &png);
  return png;
}

Rgb CheckerboardColor(double s, double t, int squares) {
  if (!std::isfinite(s) || !std::isfinite(t)) s = t = 0.5;
  squares = std::max(squares, 1);
  const int i = SquareIndex(s, squares);
  const int j = SquareIndex(t, squares);
  const bool dark = (i + j) % 2 == 0;
  // The first square index right of (above) the centre line s = 0.5 (t = 0.5).
  const int first_positive = (squares + 1) / 2;
  if (i >= first_positive && j == first_positive) return dark ? kAxisDark : kAxisLight;
  if (i >= first_positive && j > first_positive) return dark ? kQuadrantDark : kQuadrantLight;
  return dark ? kPlainDark : kPlainLight;
}

Image Checkerboard(int size, int squares) {
  assert(size >= 1 && squares >= 1);
  if (size < 1 || squares < 1) return Image{};
  Image image{size, size, std::vector<uint8_t>(size_t{3} * size * size)};
  for (int y = 0; y < size; ++y) {
    const double t = 1.0 - (y + 0.5) / size;
    for (int x = 0; x < size; ++x) {
      const Rgb color = CheckerboardColor((x + 0.5) / size, t, squares);
      std::copy(color.begin(), color.end(),
                image.rgb.begin() + 3 * (static_cast<size_t>(y) * size + x));
    }
  }
  return image;
}

}  // namespace geodex::client::cli
