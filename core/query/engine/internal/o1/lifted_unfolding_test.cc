#include "core/query/engine/internal/o1/lifted_unfolding.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/builder/builder.h"
#include "core/mesh/generators.h"
#include "core/query/engine/internal/query_parts_testing.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

// Random interior points of a mesh.
std::vector<SurfacePoint> Points(const mesh::Mesh& m, int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<SurfacePoint> out;
  for (int i = 0; i < n; ++i) {
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    out.push_back(
        {static_cast<int32_t>(u(rng) * m.num_faces()) % m.num_faces(), {a, b, 1 - a - b}});
  }
  return out;
}

TEST(UnfoldingTest, FlatSheetDistancesAreEuclidean) {
  // On a flat sheet every geodesic is straight and every unfolding is exact,
  // both in one triangle (case 3.1) and across triangles (case 3.2).
  const mesh::Mesh sheet = mesh::gen::Grid(12, 12, 2, 2);
  const testing::QueryParts parts(sheet, 30, index::MatrixLayout::kFull);
  const std::vector<SurfacePoint> points = Points(sheet, 120, 5);
  int same = 0, other = 0;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    const LiftedPoint p = parts.lifting.Lift(points[i]), q = parts.lifting.Lift(points[i + 1]);
    const double want =
        (mesh::PositionOf(sheet, points[i]) - mesh::PositionOf(sheet, points[i + 1])).norm();
    EXPECT_NEAR(parts.unfolding.Distance(p, q), want, 1e-5 * (1 + want));
    EXPECT_EQ(parts.unfolding.Distance(p, q), parts.unfolding.Distance(q, p));  // symmetric
    EXPECT_NEAR(parts.unfolding.Spread(p, q), 0, 1e-5);                         // both orders exact
    (p.triangle == q.triangle ? same : other) += 1;
  }
  EXPECT_GT(same, 0);
  EXPECT_GT(other, 0);
}

TEST(UnfoldingTest, LanesEqualOneAtATime) {
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 60);
  const std::vector<SurfacePoint> points = Points(sphere, 64, 9);
  for (size_t i = 0; i + 2 * kernel::kLanes <= points.size(); i += 2 * kernel::kLanes) {
    LiftedPoint a[kernel::kLanes], b[kernel::kLanes];
    for (int k = 0; k < kernel::kLanes; ++k) {
      a[k] = parts.lifting.Lift(points[i + k]);
      b[k] = parts.lifting.Lift(points[i + kernel::kLanes + k]);
    }
    double out[kernel::kLanes];
    parts.unfolding.DistanceLanes(a, b, out);
    for (int k = 0; k < kernel::kLanes; ++k)
      EXPECT_EQ(out[k], parts.unfolding.Distance(a[k], b[k]));
  }
}

TEST(UnfoldingTest, ToSampleIsExactAtCornersAndNearTriangles) {
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  const testing::QueryParts parts(sphere, 60);
  for (int32_t v = 0; v < 40; ++v) {
    const LiftedPoint p = parts.lifting.VertexLift(v);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(parts.unfolding.ToSample(p, p.corner[c]), p.distance[c]);
    EXPECT_TRUE(parts.unfolding.AreNear(p, p));
  }
  const index::GeodesicTriangle& t = parts.index->triangles()[0];
  LiftedPoint a, b;
  a.triangle = 0;
  b.triangle = t.neighbor[0];
  EXPECT_TRUE(parts.unfolding.AreNear(a, b));
  EXPECT_EQ(parts.unfolding.Matrix(t.corner[0], t.corner[0]), 0);
  EXPECT_GT(parts.unfolding.Matrix(t.corner[0], t.corner[1]), 0);
}

TEST(UnfoldingTest, AMatrixStoredOnceGivesTheSameAnswers) {
  // The same index with its (symmetrised) matrix written in full and once
  // (format 3): every distance agrees to the bit.
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  builder::BuildOptions options;
  options.num_samples = 50;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data = builder::BuildIndex(sphere, options, &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  const int32_t m = static_cast<int32_t>(data->samples.size());
  std::vector<float>& d = data->sample_distances;
  for (int32_t a = 0; a < m; ++a) {
    d[static_cast<size_t>(a) * m + a] = 0;
    for (int32_t b = 0; b < a; ++b) {
      const float x =
          std::min(d[static_cast<size_t>(a) * m + b], d[static_cast<size_t>(b) * m + a]);
      d[static_cast<size_t>(a) * m + b] = d[static_cast<size_t>(b) * m + a] = x;
    }
  }
  data->sample_matrix = index::MatrixLayout::kFull;
  auto full = index::Index::FromBytes(*index::SerializeIndex(*data));
  data->sample_matrix = index::MatrixLayout::kLower;
  auto packed = index::Index::FromBytes(*index::SerializeIndex(*data));
  ASSERT_TRUE(full.ok() && packed.ok());
  ASSERT_EQ((*packed)->matrix().layout(), index::MatrixLayout::kLower);
  ASSERT_LT((*packed)->size_bytes(), (*full)->size_bytes());
  const MeshView view{(*full)->positions(), (*full)->faces(), (*full)->twins()};
  const LiftedUnfolding u_full(**full, true), u_packed(**packed, true);
  const Lifting l_full(view, (*full)->vertices(), u_full);
  const Lifting l_packed(view, (*packed)->vertices(), u_packed);
  const std::vector<SurfacePoint> points = Points(sphere, 200, 3);
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    const LiftedPoint a = l_full.Lift(points[i]), b = l_full.Lift(points[i + 1]);
    EXPECT_EQ(u_full.Distance(a, b),
              u_packed.Distance(l_packed.Lift(points[i]), l_packed.Lift(points[i + 1])));
  }
  for (int32_t a = 0; a < m; ++a) {
    for (int32_t b = 0; b < m; ++b) EXPECT_EQ(u_full.Matrix(a, b), u_packed.Matrix(a, b));
  }
}

TEST(UnfoldingTest, ACodedMatrixAnswersWithinItsPrecision) {
  // The builder's default (format 4): 24-bit codes round 2.4e-7 of a
  // distance. The unfolding is not continuous in the matrix (a choice
  // between corners jumps), so the answers move more than the entries, but
  // within 1e-4 relative RMS of the float32 matrix's (tests/bench/accuracy.md,
  // "The sample matrix in 24-bit codes").
  const mesh::Mesh sphere = mesh::gen::Sphere(3, 1.0);
  builder::BuildOptions options;
  options.num_samples = 80;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data = builder::BuildIndex(sphere, options, &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  EXPECT_EQ(data->sample_matrix, index::MatrixLayout::kCoded);
  auto coded = index::Index::FromBytes(*index::SerializeIndex(*data));
  data->sample_matrix = index::MatrixLayout::kFull;
  auto full = index::Index::FromBytes(*index::SerializeIndex(*data));
  ASSERT_TRUE(full.ok() && coded.ok());
  const MeshView view{(*full)->positions(), (*full)->faces(), (*full)->twins()};
  const LiftedUnfolding u_full(**full, true), u_coded(**coded, true);
  const Lifting l_full(view, (*full)->vertices(), u_full);
  const Lifting l_coded(view, (*coded)->vertices(), u_coded);
  const std::vector<SurfacePoint> points = Points(sphere, 400, 5);
  double sum2 = 0, worst = 0;
  int n = 0;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    const double a = u_full.Distance(l_full.Lift(points[i]), l_full.Lift(points[i + 1]));
    const double b = u_coded.Distance(l_coded.Lift(points[i]), l_coded.Lift(points[i + 1]));
    if (!(a > 1e-3)) continue;
    const double e = std::abs(b - a) / a;
    sum2 += e * e;
    worst = std::max(worst, e);
    ++n;
  }
  ASSERT_GT(n, 150);
  EXPECT_LE(std::sqrt(sum2 / n), 1e-4);  // 0.01% RMS
  EXPECT_GT(worst, 0);                   // the codes do round
}

}  // namespace
}  // namespace geodex::query
