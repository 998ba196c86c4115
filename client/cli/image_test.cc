#include "client/cli/image.h"

#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client::cli {
namespace {

struct PngChunk {
  std::string type;
  std::string data;
  uint32_t stored_crc = 0;
};

uint32_t ReadBigEndian32(const std::string& bytes, size_t at) {
  return static_cast<uint32_t>(static_cast<uint8_t>(bytes[at])) << 24 |
         static_cast<uint32_t>(static_cast<uint8_t>(bytes[at + 1])) << 16 |
         static_cast<uint32_t>(static_cast<uint8_t>(bytes[at + 2])) << 8 |
         static_cast<uint32_t>(static_cast<uint8_t>(bytes[at + 3]));
}

// The chunks of a PNG file, as a reader walks them; empty when the signature
// is wrong or a chunk runs past the end.
std::vector<PngChunk> ParseChunks(const std::string& png) {
  const std::string signature = "\x89PNG\r\n\x1a\n";
  if (png.compare(0, signature.size(), signature) != 0) return {};
  std::vector<PngChunk> chunks;
  size_t at = signature.size();
  while (at < png.size()) {
    if (png.size() - at < 12) return {};
    const uint32_t length = ReadBigEndian32(png, at);
    if (png.size() - at - 12 < length) return {};
    chunks.push_back(
        {png.substr(at + 4, 4), png.substr(at + 8, length), ReadBigEndian32(png, at + 8 + length)});
    at += 12 + length;
  }
  return chunks;
}

uint32_t Crc(const PngChunk& chunk) {
  const std::string typed = chunk.type + chunk.data;
  return static_cast<uint32_t>(crc32(crc32(0L, Z_NULL, 0),
                                     reinterpret_cast<const Bytef*>(typed.data()),
                                     static_cast<uInt>(typed.size())));
}

// Decodes what EncodePng writes (8-bit RGB, filter type 0 on every
// scanline) and checks the file's structure on the way.
void ExpectPngHolds(const std::string& png, const Image& image) {
  const std::vector<PngChunk> chunks = ParseChunks(png);
  ASSERT_GE(chunks.size(), 3u);
  EXPECT_EQ(chunks.front().type, "IHDR");
  EXPECT_EQ(chunks.back().type, "IEND");
  EXPECT_EQ(chunks.back().data, "");
  std::string compressed;
  for (size_t i = 0; i < chunks.size(); ++i) {
    EXPECT_EQ(chunks[i].stored_crc, Crc(chunks[i])) << chunks[i].type;
    if (i > 0 && i + 1 < chunks.size()) {
      EXPECT_EQ(chunks[i].type, "IDAT");
      compressed += chunks[i].data;
    }
  }
  const std::string& header = chunks.front().data;
  ASSERT_EQ(header.size(), 13u);
  EXPECT_EQ(ReadBigEndian32(header, 0), static_cast<uint32_t>(image.width));
  EXPECT_EQ(ReadBigEndian32(header, 4), static_cast<uint32_t>(image.height));
  EXPECT_EQ(header.substr(8), std::string("\x08\x02\x00\x00\x00", 5));  // 8-bit RGB, plain

  const size_t row_bytes = 3 * static_cast<size_t>(image.width);
  std::vector<uint8_t> scanlines((row_bytes + 1) * image.height + 1);  // + 1: no overrun
  uLongf size = scanlines.size();
  ASSERT_EQ(uncompress(scanlines.data(), &size, reinterpret_cast<const Bytef*>(compressed.data()),
                       compressed.size()),
            Z_OK);
  ASSERT_EQ(size, (row_bytes + 1) * image.height);
  for (int y = 0; y < image.height; ++y) {
    const uint8_t* row = scanlines.data() + y * (row_bytes + 1);
    ASSERT_EQ(row[0], 0) << "filter type of row " << y;
    const std::vector<uint8_t> pixels(row + 1, row + 1 + row_bytes);
    const std::vector<uint8_t> expected(image.rgb.begin() + y * row_bytes,
                                        image.rgb.begin() + (y + 1) * row_bytes);
    ASSERT_EQ(pixels, expected) << "row " << y;
  }
}

TEST(PngEncode, ChunksCrcsAndScanlinesHoldThePixels) {
  Image image{5, 3, {}};
  for (int i = 0; i < 5 * 3 * 3; ++i) image.rgb.push_back(static_cast<uint8_t>(17 * i + 3));
  const std::string png = EncodePng(image);
  ExpectPngHolds(png, image);
  EXPECT_EQ(ParseChunks(png).size(), 3u);  // IHDR, one IDAT, IEND
}

TEST(PngEncode, OnePixel) {
  const Image image{1, 1, {255, 0, 128}};
  ExpectPngHolds(EncodePng(image), image);
}

TEST(PngEncode, LargeImageSplitsItsDataIntoBoundedChunks) {
  // Noise does not compress: over 3 MB of data in several IDAT chunks.
  Image image{1024, 1024, std::vector<uint8_t>(3 * 1024 * 1024)};
  uint64_t state = 0x9e3779b97f4a7c15u;
  for (uint8_t& byte : image.rgb) {
    state = state * 6364136223846793005u + 1442695040888963407u;
    byte = static_cast<uint8_t>(state >> 56);
  }
  const std::string png = EncodePng(image);
  ExpectPngHolds(png, image);
  const std::vector<PngChunk> chunks = ParseChunks(png);
  EXPECT_GT(chunks.size(), 4u);
  for (const PngChunk& chunk : chunks) EXPECT_LE(chunk.data.size(), size_t{1} << 20);
}

TEST(PngEncode, CheckerboardRoundTrips) {
  const Image image = Checkerboard(97, 8);
  const std::string png = EncodePng(image);
  ExpectPngHolds(png, image);
  // Flat colour compresses well even without scanline prediction.
  EXPECT_LT(png.size(), image.rgb.size() / 10);
}

TEST(PngEncode, MalformedImageGivesNothing) {
  const Image short_of_pixels{2, 2, std::vector<uint8_t>(11)};
  std::string png = "unchanged";
  EXPECT_DEBUG_DEATH(png = EncodePng(short_of_pixels), "well_formed");
#ifdef NDEBUG
  EXPECT_EQ(png, "");
  EXPECT_EQ(EncodePng(Image{0, 0, {}}), "");
#endif
}

bool IsGray(const Rgb& c) {
  return std::max({c[0], c[1], c[2]}) - std::min({c[0], c[1], c[2]}) < 20;
}
bool IsRed(const Rgb& c) { return c[0] > c[1] + 50 && c[0] > c[2] + 50; }
bool IsGreen(const Rgb& c) { return c[1] > c[0] + 40 && c[1] > c[2] + 40; }
int Brightness(const Rgb& c) { return c[0] + c[1] + c[2]; }

TEST(DecalCheckerboard, SquaresAlternateFromADarkCorner) {
  constexpr int kSquares = 8;
  const double step = 1.0 / kSquares;
  for (int i = 0; i < kSquares; ++i) {
    for (int j = 0; j < kSquares; ++j) {
      const Rgb here = CheckerboardColor((i + 0.5) * step, (j + 0.5) * step, kSquares);
      if (i + 1 < kSquares) {
        const Rgb right = CheckerboardColor((i + 1.5) * step, (j + 0.5) * step, kSquares);
        EXPECT_NE(here, right) << i << " " << j;
        // Dark squares are those with i + j even, marked or not.
        EXPECT_EQ(Brightness(here) < Brightness(right), (i + j) % 2 == 0) << i << " " << j;
      }
    }
  }
  EXPECT_LT(Brightness(CheckerboardColor(0.01, 0.01, kSquares)), 300);
}

TEST(DecalCheckerboard, OrientationMarksShowRotationsAndMirrors) {
  constexpr int n = 8;
  // The +u +v quadrant is red but for its row along the +u axis, green.
  EXPECT_TRUE(IsRed(CheckerboardColor(0.9, 0.9, n)));
  EXPECT_TRUE(IsRed(CheckerboardColor(0.6, 0.7, n)));
  EXPECT_TRUE(IsGreen(CheckerboardColor(0.9, 0.55, n)));
  EXPECT_TRUE(IsGreen(CheckerboardColor(0.55, 0.55, n)));
  EXPECT_TRUE(IsGray(CheckerboardColor(0.45, 0.55, n)));
  EXPECT_TRUE(IsGray(CheckerboardColor(0.1, 0.9, n)));
  EXPECT_TRUE(IsGray(CheckerboardColor(0.1, 0.1, n)));
  EXPECT_TRUE(IsGray(CheckerboardColor(0.9, 0.1, n)));
  EXPECT_TRUE(IsGray(CheckerboardColor(0.9, 0.45, n)));
  // No rotation by a quarter turn and no mirror (here across the diagonal,
  // the one the red quadrant alone does not reveal) maps the pattern onto
  // itself.
  bool rotation_differs = false, mirror_differs = false;
  for (int i = 0; i < 64; ++i) {
    for (int j = 0; j < 64; ++j) {
      const double s = (i + 0.5) / 64, t = (j + 0.5) / 64;
      rotation_differs |= CheckerboardColor(s, t, n) != CheckerboardColor(1 - t, s, n);
      mirror_differs |= CheckerboardColor(s, t, n) != CheckerboardColor(t, s, n);
    }
  }
  EXPECT_TRUE(rotation_differs);
  EXPECT_TRUE(mirror_differs);
}

TEST(DecalCheckerboard, OddSquaresKeepTheCentreSquarePlain) {
  EXPECT_TRUE(IsGray(CheckerboardColor(0.5, 0.5, 5)));
  EXPECT_TRUE(IsGreen(CheckerboardColor(0.7, 0.7, 5)));
  EXPECT_TRUE(IsRed(CheckerboardColor(0.9, 0.9, 5)));
}

TEST(DecalCheckerboard, OutOfRangeAndNonFiniteCoordinates) {
  EXPECT_EQ(CheckerboardColor(-3, -3, 8), CheckerboardColor(0.01, 0.01, 8));
  EXPECT_EQ(CheckerboardColor(7, 7, 8), CheckerboardColor(0.99, 0.99, 8));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(CheckerboardColor(nan, 0.1, 8), CheckerboardColor(0.5, 0.5, 8));
  EXPECT_EQ(CheckerboardColor(0.1, std::numeric_limits<double>::infinity(), 8),
            CheckerboardColor(0.5, 0.5, 8));
}

TEST(DecalCheckerboard, ImageSamplesTheTextureWithRowZeroAtTheTop) {
  constexpr int kSize = 40;
  const Image image = Checkerboard(kSize, 8);
  ASSERT_EQ(image.width, kSize);
  ASSERT_EQ(image.height, kSize);
  ASSERT_EQ(image.rgb.size(), 3u * kSize * kSize);
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const Rgb expected = CheckerboardColor((x + 0.5) / kSize, 1 - (y + 0.5) / kSize, 8);
      const size_t at = 3 * (static_cast<size_t>(y) * kSize + x);
      ASSERT_EQ((Rgb{image.rgb[at], image.rgb[at + 1], image.rgb[at + 2]}), expected)
          << x << " " << y;
    }
  }
  // Top right is the +u +v quadrant.
  EXPECT_TRUE(IsRed({image.rgb[3 * (kSize - 1)], image.rgb[3 * (kSize - 1) + 1],
                     image.rgb[3 * (kSize - 1) + 2]}));
}

}  // namespace
}  // namespace geodex::client::cli
