#include "core/sampling/farthest_point_sampling.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::sampling {
namespace {

uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

int32_t FarthestVertex(const mesh::Mesh& mesh, const SampleSet& set,
                       const std::vector<uint8_t>& mask, std::span<const double> spacing_weight) {
  int32_t best = mesh::kNone;
  double best_distance = -1;
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    if (!mesh.IsReferenced(v) || (!mask.empty() && !mask[v])) continue;
    const double d = spacing_weight.empty() ? set.distance[v] : spacing_weight[v] * set.distance[v];
    if (d > best_distance) {
      best = v;
      best_distance = d;
    }
  }
  return best_distance > 0 ? best : mesh::kNone;
}

absl::Status AddSample(geodesic::VertexGeodesicSolver& solver, int32_t v, SampleSet* set) {
  const mesh::Mesh& mesh = solver.mesh();
  if (v < 0 || v >= mesh.num_vertices() || !mesh.IsReferenced(v)) {
    return absl::InvalidArgumentError(absl::StrFormat("vertex %d cannot be a sample", v));
  }
  if (set->distance[v] == 0) {
    return absl::InvalidArgumentError(absl::StrFormat("vertex %d is already a sample", v));
  }
  geodesic::VertexGeodesicOptions options;
  options.initial_distance = set->distance;
  GEODEX_RETURN_IF_ERROR(solver.Propagate({v}, options));
  const int32_t index = static_cast<int32_t>(set->samples.size());
  set->samples.push_back(v);
  for (int32_t u = 0; u < mesh.num_vertices(); ++u) {
    // Vertices the new sample reached strictly sooner now belong to its cell.
    if (solver.NearestSource(u) == 0) {
      set->distance[u] = solver.VertexDistance(u);
      set->nearest[u] = index;
    }
  }
  set->distance[v] = 0;
  set->nearest[v] = index;
  return absl::OkStatus();
}

absl::StatusOr<SampleSet> FarthestPointSampling(const mesh::Mesh& mesh, int32_t num_samples,
                                                uint64_t seed,
                                                std::span<const double> spacing_weight) {
  int32_t referenced = 0;
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) referenced += mesh.IsReferenced(v);
  if (num_samples < 1 || num_samples > referenced) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "cannot take %d samples from a mesh with %d referenced vertices", num_samples, referenced));
  }
  if (!spacing_weight.empty()) {
    if (spacing_weight.size() != static_cast<size_t>(mesh.num_vertices())) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%d spacing weights for a mesh of %d vertices", spacing_weight.size(),
                          mesh.num_vertices()));
    }
    for (size_t v = 0; v < spacing_weight.size(); ++v) {
      if (!(spacing_weight[v] > 0) || !std::isfinite(spacing_weight[v])) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "spacing weight %g of vertex %d is not positive and finite", spacing_weight[v], v));
      }
    }
  }
  geodesic::VertexGeodesicSolver solver(mesh);
  int32_t start = static_cast<int32_t>(SplitMix64(seed) % mesh.num_vertices());
  while (!mesh.IsReferenced(start)) start = (start + 1) % mesh.num_vertices();

  SampleSet set;
  set.distance.assign(mesh.num_vertices(), geodesic::kInfinity);
  set.nearest.assign(mesh.num_vertices(), mesh::kNone);
  {
    GEODEX_RETURN_IF_ERROR(solver.Propagate({start}));
    SampleSet probe;
    probe.distance = solver.VertexDistances();
    const int32_t first = FarthestVertex(mesh, probe);
    GEODEX_RETURN_IF_ERROR(AddSample(solver, first == mesh::kNone ? start : first, &set));
  }
  while (static_cast<int32_t>(set.samples.size()) < num_samples) {
    const int32_t next = FarthestVertex(mesh, set, {}, spacing_weight);
    if (next == mesh::kNone) break;  // every vertex is a sample
    GEODEX_RETURN_IF_ERROR(AddSample(solver, next, &set));
  }
  return set;
}

}  // namespace geodex::sampling
