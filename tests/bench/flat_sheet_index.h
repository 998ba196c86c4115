#pragma once

// A synthetic index of a flat sheet, for server_bench's memory measurement:
// every section filled and valid, distances exact, and of any size without
// the hours a real build of that size takes.

#include "core/index/index.h"

namespace geodex::bench {

// A unit-spaced planar grid of `cells` x `cells` pairs of geodesic triangles
// (samples at the coarse grid points, (cells + 1)^2 of them), each coarse
// cell split into `fine` x `fine` mesh cells. Distances on a flat sheet are
// Euclidean, so every section is exact. `cells` and `fine` must be >= 1.
index::IndexData FlatSheetIndex(int cells, int fine);

}  // namespace geodex::bench
