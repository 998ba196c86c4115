#include "core/query/engine/internal/fields/distance_field.h"

#include <cmath>
#include <limits>

#include "core/mesh/generators.h"
#include "core/query/engine/internal/query_parts_testing.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

TEST(DistanceFieldTest, FlatSheetFieldIsTheDistanceToTheNearestSource) {
  const mesh::Mesh sheet = mesh::gen::Grid(10, 10, 2, 2);
  const testing::QueryParts parts(sheet, 20, index::MatrixLayout::kFull);
  const std::vector<SurfacePoint> sources = {{3, {0.2, 0.3, 0.5}}, {150, {0.6, 0.2, 0.2}}};
  const DistanceField field = ApproximateField(parts.view, parts.lifting, parts.unfolding, sources);
  ASSERT_EQ(field.distance.size(), static_cast<size_t>(sheet.num_vertices()));
  for (int32_t v = 0; v < sheet.num_vertices(); ++v) {
    double best = std::numeric_limits<double>::infinity();
    int32_t nearest = -1;
    for (size_t s = 0; s < sources.size(); ++s) {
      const double d = (sheet.position(v) - mesh::PositionOf(sheet, sources[s])).norm();
      if (d < best) best = d, nearest = static_cast<int32_t>(s);
    }
    EXPECT_NEAR(field.distance[v], best, 1e-5 * (1 + best)) << "vertex " << v;
    if (std::abs(field.distance[v] - best) < 1e-3) {
      EXPECT_EQ(field.nearest[v], nearest);
    }
  }
}

}  // namespace
}  // namespace geodex::query
