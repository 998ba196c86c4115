#pragma once

// The sample spacing, the length every distance scale of the product is
// measured in: L = sqrt(2 A / (sqrt(3) m)), the edge of an equilateral
// geodesic triangle when m samples tile a surface of area A evenly (Xin,
// Ying & He 2012, §7, where errors are reported by multiples of it). With
// the index's own m it places the split between walked and O(1) answers;
// with m = 1000 (L1000) it is a unit fixed by the surface, not by the index.
//
// Written once for the library; the client keeps its own copy because it
// depends on the proto only (client/cli/bench.h).
//
// Thread safety: a pure function.

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace geodex::geometry {

// L of `num_samples` samples (at least 1) on a surface of area `area`.
inline double SampleSpacing(double area, int64_t num_samples) {
  return std::sqrt(2 * area /
                   (std::sqrt(3.0) * static_cast<double>(std::max<int64_t>(num_samples, 1))));
}

}  // namespace geodex::geometry
