#include "core/index/derived_sections.h"

#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/edge_groups.h"
#include "core/common/status_macros.h"

namespace geodex::index::internal {

absl::StatusOr<std::vector<int32_t>> DeriveTwins(std::span<const int32_t> faces,
                                                 absl::StatusCode code) {
  const int32_t nh = static_cast<int32_t>(faces.size());
  auto ends = [&](int32_t h) {
    return std::pair<int32_t, int32_t>(faces[h], faces[h % 3 == 2 ? h - 2 : h + 1]);
  };
  std::vector<int32_t> twins(nh, -1);
  GEODEX_RETURN_IF_ERROR(
      ForEachEdge(nh, ends, [&](std::span<const int32_t> group, int64_t a, int64_t b) {
        if (group.size() > 2) {
          return absl::Status(code, absl::StrFormat("twins: edge (%d, %d) is shared by %d faces", a,
                                                    b, group.size()));
        }
        if (group.size() == 2) {
          const int32_t h0 = group[0], h1 = group[1];
          if (faces[h0] == faces[h1]) {
            return absl::Status(
                code, absl::StrFormat("twins: faces %d and %d run edge (%d, %d) the same way",
                                      h0 / 3, h1 / 3, a, b));
          }
          twins[h0] = h1;
          twins[h1] = h0;
        }
        return absl::OkStatus();
      }));
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
