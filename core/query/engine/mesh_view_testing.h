#pragma once

// Test-only: the twins of a small face list, for MeshViews made by hand.

#include <cstdint>
#include <vector>

namespace geodex::query::testing {

// Twins of the half-edges 3 f + i (corner i -> i+1): the reversed edge, or -1.
inline std::vector<int32_t> Twins(const std::vector<int32_t>& faces) {
  std::vector<int32_t> twins(faces.size(), -1);
  for (size_t h = 0; h < faces.size(); ++h) {
    const int32_t a = faces[h], b = faces[h - h % 3 + (h % 3 + 1) % 3];
    for (size_t g = 0; g < faces.size(); ++g) {
      if (faces[g] == b && faces[g - g % 3 + (g % 3 + 1) % 3] == a) twins[h] = g;
    }
  }
  return twins;
}

}  // namespace geodex::query::testing
