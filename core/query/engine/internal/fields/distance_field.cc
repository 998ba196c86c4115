#include "core/query/engine/internal/fields/distance_field.h"

#include <algorithm>
#include <limits>
#include <vector>

namespace geodex::query {

DistanceField ApproximateField(const MeshView& view, const Lifting& lifting,
                               const LiftedUnfolding& unfolding,
                               std::span<const SurfacePoint> sources) {
  std::vector<LiftedPoint> lifted;
  std::vector<mesh::Vec3> at;
  for (const SurfacePoint& source : sources) {
    lifted.push_back(lifting.Lift(source));
    at.push_back(view.PositionOf(source));
  }
  DistanceField field;
  const int32_t n = static_cast<int32_t>(view.positions.size() / 3);
  field.distance.assign(n, std::numeric_limits<double>::infinity());
  field.nearest.assign(n, -1);
  for (int32_t v = 0; v < n; ++v) {
    const LiftedPoint x = lifting.VertexLift(v);
    if (x.triangle < 0) continue;
    for (size_t s = 0; s < lifted.size(); ++s) {
      double d = unfolding.Distance(lifted[s], x);
      // Near pairs: at least the straight line (no surface path is shorter).
      if (unfolding.AreNear(lifted[s], x)) d = std::max(d, (at[s] - view.Position(v)).norm());
      if (d < field.distance[v]) {
        field.distance[v] = d;
        field.nearest[v] = static_cast<int32_t>(s);
      }
    }
  }
  return field;
}

}  // namespace geodex::query
