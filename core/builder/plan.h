#pragma once

// The plan of an index (paper §4.1): its samples, their geodesic Voronoi
// diagram at vertex resolution and the dual geodesic Delaunay triangulation,
// as builder.h's MakePlan makes it and the rows and merge phases read it.
//
// Thread safety: a Plan is a plain value, immutable once made.

#include <array>
#include <cstdint>
#include <vector>

#include "core/triangulation/geodesic_triangulation.h"

namespace geodex::builder {

struct Plan {
  uint64_t mesh_hash = 0;
  int32_t requested_samples = 0;
  uint64_t seed = 0;
  std::vector<int32_t> samples;  // vertex of each sample
  std::vector<int32_t> nearest;  // Voronoi cell (sample) of each vertex, kNone if unreferenced
  // Per sample: the largest distance from it to a vertex of its cell
  // (bounds how far a carried row's propagation must go; builder.h
  // ComputeRows). Empty in a plan read from an older work directory.
  std::vector<double> cell_radius;
  std::vector<std::array<int32_t, 3>> triangles;
  std::vector<std::array<int32_t, 3>> neighbors;
  triangulation::RepairReport repair;
  triangulation::EdgeStats edge_stats;  // of the final geodesic edges
  // The final geodesic edges when traced. Only in the process that made the
  // plan: the work directory keeps edge_stats, not the paths.
  std::vector<triangulation::GeodesicEdge> edges;
  double sampling_seconds = 0;
  double triangulation_seconds = 0;

  int32_t num_samples() const { return static_cast<int32_t>(samples.size()); }
  // Samples adjacent to `a` in the triangulation, sorted.
  std::vector<std::vector<int32_t>> SampleNeighbors() const;
};

// Vertices whose cell is `a` or one of `neighbors_of_a` (a's entry of
// SampleNeighbors), in increasing order: those whose distance to `a` a
// sample's row carries.
std::vector<int32_t> CellVertices(const Plan& plan, const std::vector<int32_t>& neighbors_of_a,
                                  int32_t a);

}  // namespace geodex::builder
