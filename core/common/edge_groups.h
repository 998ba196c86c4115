#pragma once

// Half-edges grouped by the undirected edge they run along: the step that
// pairs twins when a mesh is loaded, when a soup is repaired and when an index
// derives the twins it left out. The three must agree on which half-edges
// share an edge and in which order they come, so the grouping is written
// once.

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <span>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "core/common/status_macros.h"

namespace geodex {

// Calls visit(group, a, b) once for each undirected edge (a, b), a <= b, of
// the half-edges 0 .. num_halfedges - 1, whose vertices ends(h) gives as a
// pair (origin, destination). The edges come in increasing (a, b); a group
// lists the edge's half-edges in increasing id. Returns the first error a
// visit returns, without visiting the edges after it.
template <typename Ends, typename Visit>
absl::Status ForEachEdge(int32_t num_halfedges, Ends&& ends, Visit&& visit) {
  auto key = [&](int32_t h) {
    const auto [origin, dest] = ends(h);
    const int64_t a = origin, b = dest;
    return std::pair<int64_t, int64_t>(std::min(a, b), std::max(a, b));
  };
  std::vector<int32_t> order(num_halfedges);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int32_t x, int32_t y) {
    const auto kx = key(x), ky = key(y);
    return kx != ky ? kx < ky : x < y;
  });
  for (int32_t i = 0; i < num_halfedges;) {
    const auto edge = key(order[i]);
    int32_t j = i + 1;
    while (j < num_halfedges && key(order[j]) == edge) ++j;
    GEODEX_RETURN_IF_ERROR(
        visit(std::span<const int32_t>(order.data() + i, j - i), edge.first, edge.second));
    i = j;
  }
  return absl::OkStatus();
}

}  // namespace geodex
