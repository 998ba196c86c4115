#include "core/builder/plan.h"

#include <algorithm>

#include "core/mesh/mesh.h"

namespace geodex::builder {

std::vector<std::vector<int32_t>> Plan::SampleNeighbors() const {
  std::vector<std::vector<int32_t>> out(num_samples());
  for (const auto& t : triangles) {
    for (int i = 0; i < 3; ++i) {
      out[t[i]].push_back(t[(i + 1) % 3]);
      out[t[i]].push_back(t[(i + 2) % 3]);
    }
  }
  for (auto& list : out) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return out;
}

std::vector<int32_t> CellVertices(const Plan& plan, const std::vector<int32_t>& neighbors_of_a,
                                  int32_t a) {
  std::vector<uint8_t> member(plan.num_samples(), 0);
  member[a] = 1;
  for (int32_t b : neighbors_of_a) member[b] = 1;
  std::vector<int32_t> out;
  for (int32_t v = 0; v < static_cast<int32_t>(plan.nearest.size()); ++v) {
    if (plan.nearest[v] != mesh::kNone && member[plan.nearest[v]]) out.push_back(v);
  }
  return out;
}

}  // namespace geodex::builder
