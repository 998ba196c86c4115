#include "core/validation/error_map.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/common/threads.h"
#include "core/geodesic/vertex_geodesic.h"
#include "core/query/engine/query_engine.h"
#include "core/validation/pair_sampling.h"

namespace geodex::validation {
namespace {

// A third of the area of each incident face.
std::vector<double> VertexAreas(const mesh::Mesh& mesh) {
  std::vector<double> area(mesh.num_vertices(), 0.0);
  for (int32_t f = 0; f < mesh.num_faces(); ++f) {
    const double a = mesh.Area(f) / 3;
    for (int32_t v : mesh.face(f)) area[v] += a;
  }
  return area;
}

}  // namespace

absl::StatusOr<std::vector<double>> VertexErrorMap(const mesh::Mesh& mesh,
                                                   std::shared_ptr<const index::Index> index,
                                                   const ErrorMapOptions& options) {
  if (index->num_vertices() != mesh.num_vertices() || index->num_faces() != mesh.num_faces()) {
    return absl::FailedPreconditionError("the index was not built from this mesh");
  }
  GEODEX_ASSIGN_OR_RETURN(auto engine, query::QueryEngine::Create(index));
  const int32_t n = mesh.num_vertices();
  std::vector<mesh::SurfacePoint> at_vertex(n);
  for (int32_t v = 0; v < n; ++v) {
    if (mesh.IsReferenced(v)) at_vertex[v] = *mesh::VertexPoint(mesh, v);
  }
  const double near = query::kRefineScale * engine->scale_length();
  const std::vector<mesh::SurfacePoint> sources =
      RandomSurfacePoints(mesh, options.num_sources, options.seed);
  // Squared relative errors per source, summed in source order afterwards so
  // that the map does not depend on the thread count.
  std::vector<std::vector<float>> squared(sources.size());
  std::vector<absl::Status> errors(sources.size());
  std::atomic<size_t> next{0};
  auto worker = [&] {
    geodesic::VertexGeodesicSolver solver(mesh);
    for (size_t s; (s = next.fetch_add(1)) < sources.size();) {
      errors[s] = solver.Propagate({sources[s]});
      if (!errors[s].ok()) continue;
      std::vector<float>& out = squared[s];
      out.assign(n, -1.0f);  // -1: not measured
      for (int32_t v = 0; v < n; ++v) {
        const double exact = solver.VertexDistance(v);
        if (!mesh.IsReferenced(v) || !(exact >= near) || !std::isfinite(exact)) continue;
        const double e = (engine->O1Distance(sources[s], at_vertex[v]) - exact) / exact;
        out[v] = static_cast<float>(e * e);
      }
    }
  };
  const int threads =
      std::clamp(common::ThreadCount(options.threads), 1, std::max(1, options.num_sources));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  for (const absl::Status& status : errors) GEODEX_RETURN_IF_ERROR(status);

  std::vector<double> sum(n, 0.0);
  std::vector<int32_t> count(n, 0);
  for (const std::vector<float>& out : squared) {
    for (int32_t v = 0; v < n; ++v) {
      if (out[v] >= 0) {
        sum[v] += out[v];
        ++count[v];
      }
    }
  }
  // Averaged over each geodesic triangle, area-weighted.
  const std::vector<double> area = VertexAreas(mesh);
  const auto records = index->vertices();
  std::vector<double> triangle_sum(index->num_triangles(), 0.0);
  std::vector<double> triangle_area(index->num_triangles(), 0.0);
  bool any = false;
  for (int32_t v = 0; v < n; ++v) {
    const int32_t t = records[v].triangle;
    if (count[v] == 0 || t < 0) continue;
    triangle_sum[t] += area[v] * sum[v] / count[v];
    triangle_area[t] += area[v];
    any = true;
  }
  if (!any) return absl::InternalError("error map: no vertex was measured");
  std::vector<double> map(n, 0.0);
  for (int32_t v = 0; v < n; ++v) {
    const int32_t t = records[v].triangle;
    if (mesh.IsReferenced(v) && t >= 0 && triangle_area[t] > 0) {
      map[v] = triangle_sum[t] / triangle_area[t];
    }
  }
  return map;
}

absl::StatusOr<std::vector<double>> SpacingWeights(const mesh::Mesh& mesh,
                                                   const std::vector<double>& error_map,
                                                   double exponent) {
  if (error_map.size() != static_cast<size_t>(mesh.num_vertices())) {
    return absl::InvalidArgumentError(absl::StrFormat("an error map of %d entries for %d vertices",
                                                      error_map.size(), mesh.num_vertices()));
  }
  const std::vector<double> area = VertexAreas(mesh);
  double weighted = 0, total = 0;
  for (size_t v = 0; v < error_map.size(); ++v) {
    if (!(error_map[v] >= 0) || !std::isfinite(error_map[v])) {
      return absl::InvalidArgumentError(
          absl::StrFormat("error map entry %g of vertex %d", error_map[v], v));
    }
    weighted += area[v] * error_map[v];
    total += area[v];
  }
  std::vector<double> weight(error_map.size(), 1.0);
  if (!(weighted > 0) || !(total > 0)) return weight;  // no error anywhere: plain sampling
  const double mean = weighted / total;
  double smallest = std::numeric_limits<double>::infinity();
  for (size_t v = 0; v < error_map.size(); ++v) {
    weight[v] = std::pow(error_map[v] / mean, exponent);
    if (weight[v] > 0) smallest = std::min(smallest, weight[v]);
  }
  for (double& w : weight) {
    if (!(w > 0)) w = smallest;
  }
  return weight;
}

}  // namespace geodex::validation
