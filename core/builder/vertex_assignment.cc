#include "core/builder/vertex_assignment.h"

#include <algorithm>
#include <array>

#include "core/geodesic/exact_geodesic.h"
#include "core/geometry/planar_unfolding.h"

namespace geodex::builder {

using mesh::kNone;

AssignmentCounts AssignVerticesToTriangles(
    const mesh::Mesh& mesh, const Plan& plan,
    absl::FunctionRef<double(int32_t a, int32_t b)> sample_distance,
    absl::FunctionRef<double(int32_t v, int32_t b)> vertex_distance,
    std::vector<index::VertexRecord>* records) {
  // Triangles around each sample.
  std::vector<std::vector<int32_t>> incident(plan.num_samples());
  for (int32_t t = 0; t < static_cast<int32_t>(plan.triangles.size()); ++t) {
    for (int32_t a : plan.triangles[t]) incident[a].push_back(t);
  }

  const int32_t nv = mesh.num_vertices();
  records->resize(nv);
  AssignmentCounts counts;
  for (int32_t v = 0; v < nv; ++v) {
    index::VertexRecord& record = (*records)[v];
    record = {kNone, {0, 0, 0}};
    const int32_t a = plan.nearest[v];
    if (!mesh.IsReferenced(v) || a == kNone) continue;
    ++counts.referenced;
    double best_score = -geodesic::kInfinity;
    double best_max = 0;
    for (int32_t t : incident[a]) {
      const auto& corners = plan.triangles[t];
      std::array<double, 3> d;
      for (int i = 0; i < 3; ++i) d[i] = vertex_distance(v, corners[i]);
      const auto lambda = geometry::UnfoldedBarycentric(sample_distance(corners[0], corners[1]),
                                                        sample_distance(corners[1], corners[2]),
                                                        sample_distance(corners[2], corners[0]), d);
      const double score = std::min({lambda[0], lambda[1], lambda[2]});
      if (score > best_score) {
        best_score = score;
        best_max = std::max({lambda[0], lambda[1], lambda[2]});
        record.triangle = t;
        for (int i = 0; i < 3; ++i) record.distance[i] = static_cast<float>(d[i]);
      }
    }
    if (record.triangle == kNone) {
      ++counts.unassigned;
    } else if (best_score < -0.01 || best_max > 1.01) {
      ++counts.outside;
    }
  }
  return counts;
}

}  // namespace geodex::builder
