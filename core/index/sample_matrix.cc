#include "core/index/sample_matrix.h"

#include <cmath>

namespace geodex::index {

double DistanceCode::ScaleFor(double largest) {
  return largest > 0 && std::isfinite(largest) ? largest / Unit(kLargest) : 1.0;
}

uint32_t DistanceCode::Encode(double d, double scale) {
  if (!(d < std::numeric_limits<double>::infinity())) return kInfinity;
  const double unit = std::max(d, 0.0) / scale;
  if (unit >= Unit(kLargest)) return kLargest;
  // The code whose float lies just below unit + 2^-8, then the nearer of it
  // and the next one: Unit is increasing in the code.
  const uint32_t bits = std::bit_cast<uint32_t>(static_cast<float>(unit + 0x1p-8));
  const int64_t guess = (static_cast<int64_t>(bits) - (int64_t{119} << 23)) >> 2;
  int64_t c = std::clamp<int64_t>(guess, 0, kLargest);
  while (c > 0 && Unit(static_cast<uint32_t>(c)) > unit) --c;
  while (c < kLargest && Unit(static_cast<uint32_t>(c + 1)) <= unit) ++c;
  if (c < kLargest &&
      Unit(static_cast<uint32_t>(c + 1)) - unit < unit - Unit(static_cast<uint32_t>(c))) {
    ++c;
  }
  return static_cast<uint32_t>(c);
}

}  // namespace geodex::index
