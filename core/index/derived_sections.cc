#include "core/index/derived_sections.h"

#include <algorithm>
#include <numeric>
#include <utility>

#include "absl/strings/str_format.h"

namespace geodex::index::internal {

absl::StatusOr<std::vector<int32_t>> DeriveTwins(std::span<const int32_t> faces,
                                                 absl::StatusCode code) {
  const int32_t nh = static_cast<int32_t>(faces.size());
  auto origin = [&](int32_t h) { return faces[h]; };
  auto dest = [&](int32_t h) { return faces[h % 3 == 2 ? h - 2 : h + 1]; };
  auto key = [&](int32_t h) {
    const int64_t a = origin(h), b = dest(h);
    return std::pair<int64_t, int64_t>(std::min(a, b), std::max(a, b));
  };
  std::vector<int32_t> order(nh);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int32_t x, int32_t y) {
    const auto kx = key(x), ky = key(y);
    return kx != ky ? kx < ky : x < y;
  });
  std::vector<int32_t> twins(nh, -1);
  for (int32_t i = 0; i < nh;) {
    int32_t j = i + 1;
    while (j < nh && key(order[j]) == key(order[i])) ++j;
    const auto [a, b] = key(order[i]);
    if (j - i > 2) {
      return absl::Status(code, absl::StrFormat("twins: edge (%d, %d) is shared by %d faces", a, b, j - i));
    }
    if (j - i == 2) {
      const int32_t h0 = order[i], h1 = order[i + 1];
      if (origin(h0) == origin(h1)) {
        return absl::Status(code, absl::StrFormat("twins: faces %d and %d run edge (%d, %d) the same way",
                                                  h0 / 3, h1 / 3, a, b));
      }
      twins[h0] = h1;
      twins[h1] = h0;
    }
    i = j;
  }
  return twins;
}

std::vector<VertexRecord> WithoutCorners(std::span<const VertexRecordWithCorners> records) {
  std::vector<VertexRecord> out(records.size());
  for (size_t v = 0; v < records.size(); ++v) {
    out[v].triangle = records[v].triangle;
    std::copy(std::begin(records[v].distance), std::end(records[v].distance),
              std::begin(out[v].distance));
  }
  return out;
}

std::vector<VertexRecordWithCorners> WithCorners(std::span<const VertexRecord> records,
                                                 std::span<const GeodesicTriangle> triangles) {
  std::vector<VertexRecordWithCorners> out(records.size());
  for (size_t v = 0; v < records.size(); ++v) {
    const VertexRecord& r = records[v];
    VertexRecordWithCorners& w = out[v];
    w.triangle = r.triangle;
    for (int k = 0; k < 3; ++k) {
      w.corner[k] = r.triangle == -1 ? -1 : triangles[r.triangle].corner[k];
      w.distance[k] = r.distance[k];
    }
    w.flags = 0;
  }
  return out;
}

}  // namespace geodex::index::internal
