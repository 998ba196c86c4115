#pragma once

// The sample distance matrix d(a, b) of an index, in whichever layout its
// file stores it (index_format.h):
//
//   kFull   float[m][m], row-major (1.x, 2.x);
//   kLower  float, the strictly lower triangle (3.0);
//   kCoded  24-bit codes of the strictly lower triangle (4.0).
//
// The code of a distance d is a float with 21 mantissa bits over 8 octaves:
// value(c) = scale * (F(c) - 2^-8), F(c) the float whose bits are
// (c << 2) + bits(2^-8). Rounding to the nearest code errs at most 2^-22
// (2.4e-7) of d + scale / 256: 2.4e-7 of d for the long distances that
// make most of a matrix, up to 4.8e-7 at d = scale / 256, and
// scale * 2^-30 below. Why 24 bits and not 16, though the O(1) answer
// errs far more than either: it is not continuous in the matrix (an
// unfolding that chooses between two corners or two sides jumps when an
// entry crosses the choice), and with 16 bits enough entries cross to move
// the answers beyond what the float32 matrix gives by more than the limit
// the codes are held to (tests/bench/accuracy.md, "The sample matrix in
// 24-bit codes").
// Code 0xFFFFFF is +inf (samples on different components). Decoding is
// three byte loads, a shift, an add and a multiply: no table.
//
// Thread safety: an immutable view; every method is const and thread-safe.

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

namespace geodex::index {

enum class MatrixLayout : uint8_t { kFull, kLower, kCoded };

// A code as stored: three bytes, little-endian, no alignment.
struct PackedCode {
  uint8_t bytes[3];
};
static_assert(sizeof(PackedCode) == 3 && alignof(PackedCode) == 1);

// The 24-bit code of a distance (see above).
class DistanceCode {
 public:
  static constexpr uint32_t kInfinity = 0xFFFFFF;
  static constexpr uint32_t kLargest = 0xFFFFFE;  // the largest finite code

  // The scale that gives `largest` (the largest finite distance, >= 0) the
  // largest finite code; 1 when there is none.
  static double ScaleFor(double largest);
  // The nearest code of `d` (>= 0 or +inf) for `scale`.
  static uint32_t Encode(double d, double scale);
  // value(c) for scale 1: exact in double.
  static double Unit(uint32_t c) {
    constexpr uint32_t kBias = 119u << 23;  // the bits of 2^-8
    return static_cast<double>(std::bit_cast<float>((c << 2) + kBias)) - 0x1p-8;
  }
  static double Decode(uint32_t c, double scale) {
    return c == kInfinity ? std::numeric_limits<double>::infinity() : scale * Unit(c);
  }
  static PackedCode Pack(uint32_t c) {
    return {{static_cast<uint8_t>(c), static_cast<uint8_t>(c >> 8), static_cast<uint8_t>(c >> 16)}};
  }
  static uint32_t Unpack(const PackedCode& p) {
    return uint32_t{p.bytes[0]} | uint32_t{p.bytes[1]} << 8 | uint32_t{p.bytes[2]} << 16;
  }
};

class SampleMatrix {
 public:
  SampleMatrix() = default;
  static SampleMatrix Full(std::span<const float> full, int32_t num_samples) {
    return SampleMatrix(MatrixLayout::kFull, full.data(), num_samples, 0);
  }
  static SampleMatrix Lower(std::span<const float> lower, int32_t num_samples) {
    return SampleMatrix(MatrixLayout::kLower, lower.data(), num_samples, 0);
  }
  static SampleMatrix Coded(std::span<const PackedCode> codes, int32_t num_samples, double scale) {
    return SampleMatrix(MatrixLayout::kCoded, codes.data(), num_samples, scale);
  }

  MatrixLayout layout() const { return layout_; }
  int32_t num_samples() const { return num_samples_; }
  // The coded layout's scale (0 for the others).
  double scale() const { return scale_; }

  // d(a, b), a and b in [0, num_samples()).
  double operator()(int32_t a, int32_t b) const {
    switch (layout_) {
      case MatrixLayout::kFull:
        return static_cast<const float*>(data_)[static_cast<size_t>(a) * num_samples_ + b];
      case MatrixLayout::kLower:
        return a == b ? 0.0 : static_cast<const float*>(data_)[LowerOffset(a, b)];
      case MatrixLayout::kCoded:
        return a == b ? 0.0
                      : DistanceCode::Decode(
                            DistanceCode::Unpack(
                                static_cast<const PackedCode*>(data_)[LowerOffset(a, b)]),
                            scale_);
    }
    return 0;
  }
  // Where d(a, b) lives, for prefetching.
  const void* Address(int32_t a, int32_t b) const {
    switch (layout_) {
      case MatrixLayout::kFull:
        return static_cast<const float*>(data_) + static_cast<size_t>(a) * num_samples_ + b;
      case MatrixLayout::kLower:
        return static_cast<const float*>(data_) + (a == b ? 0 : LowerOffset(a, b));
      case MatrixLayout::kCoded:
        return static_cast<const PackedCode*>(data_) + (a == b ? 0 : LowerOffset(a, b));
    }
    return data_;
  }
  // The offset of d(a, b), a != b, in a strictly lower triangle.
  static size_t LowerOffset(int32_t a, int32_t b) {
    const size_t hi = static_cast<size_t>(std::max(a, b)), lo = static_cast<size_t>(std::min(a, b));
    return hi * (hi - 1) / 2 + lo;
  }

 private:
  SampleMatrix(MatrixLayout layout, const void* data, int32_t num_samples, double scale)
      : layout_(layout), data_(data), num_samples_(num_samples), scale_(scale) {}

  MatrixLayout layout_ = MatrixLayout::kFull;
  const void* data_ = nullptr;
  int32_t num_samples_ = 0;
  double scale_ = 0;
};

}  // namespace geodex::index
