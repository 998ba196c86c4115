#pragma once

// Farthest-point sampling on a triangle mesh with exact geodesic distances
// (paper §4.1, after Peyré & Cohen 2006), plus the geodesic Voronoi diagram of
// the samples at vertex resolution, which comes for free.
//
// Samples are mesh vertices. The first sample follows a documented rule: the
// seed picks a start vertex (SplitMix64(seed) modulo the vertex count, moved
// up to the next referenced vertex); the first sample is the vertex farthest
// from it. Each further sample is the vertex farthest from all samples so far
// (+inf first, so every connected component gets sampled; ties go to the
// lowest vertex id). Each new sample runs one propagation that starts from the
// current distances and stops wherever it gets no closer, so sampling costs
// far less than one full propagation per sample.
//
// Thread safety: the functions are reentrant; a SampleSet is a plain value.

#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geodesic/vertex_geodesic.h"
#include "core/mesh/mesh.h"

namespace geodex::sampling {

struct SampleSet {
  std::vector<int32_t> samples;  // vertex of each sample
  std::vector<double> distance;  // per vertex: distance to the nearest sample
  std::vector<int32_t> nearest;  // per vertex: index of the nearest sample (kNone if none)
};

// With `spacing_weight` (one positive finite entry per vertex), each further
// sample is the vertex of largest spacing_weight[v] x distance instead, so
// that samples lie about 1 / spacing_weight closer together where it is large
// (error-driven placement, core/validation/error_map.h); empty: plain
// farthest-point sampling.
// Errors: InvalidArgument if num_samples < 1 or exceeds the referenced vertex
// count, or for a spacing_weight of the wrong size or with an entry that is
// not positive and finite; errors of the geodesic engine.
absl::StatusOr<SampleSet> FarthestPointSampling(const mesh::Mesh& mesh, int32_t num_samples,
                                                uint64_t seed,
                                                std::span<const double> spacing_weight = {});

// Adds vertex `v` as a new sample and updates distances and Voronoi labels
// where it is closer. Errors: InvalidArgument if `v` is already a sample.
absl::Status AddSample(geodesic::VertexGeodesicSolver& solver, int32_t v, SampleSet* set);

// The referenced vertex farthest from the samples (+inf first, ties to the
// lowest id), restricted to vertices with `mask[v]` when `mask` is non-empty;
// with `spacing_weight`, the distances are multiplied by it first.
// Returns mesh::kNone when no candidate exists.
int32_t FarthestVertex(const mesh::Mesh& mesh, const SampleSet& set,
                       const std::vector<uint8_t>& mask = {},
                       std::span<const double> spacing_weight = {});

}  // namespace geodex::sampling
