#include "core/validation/calibration.h"

#include <algorithm>
#include <cmath>

#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/geodesic/vertex_geodesic.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_repair.h"
#include "core/query/engine/query_engine.h"
#include "gtest/gtest.h"

namespace geodex::validation {
namespace {

// The index of `m` with `samples` samples.
index::IndexData IndexDataOf(const mesh::Mesh& m, int32_t samples = 80) {
  builder::BuildOptions options;
  options.num_samples = samples;
  options.threads = 2;
  builder::BuildSummary summary;
  auto data = builder::BuildIndex(m, options, &summary);
  EXPECT_TRUE(data.ok()) << data.status();
  return *std::move(data);
}

TEST(CalibrationTest, BoundsAreSaneAndDeterministic) {
  const mesh::Mesh m = mesh::gen::Sphere(4, 1.0);
  index::IndexData data = IndexDataOf(m);
  ASSERT_TRUE(AddCalibration(m, data).ok());
  ASSERT_EQ(data.accuracy.size(), 1u);
  const index::AccuracyRecord& r = data.accuracy[0];
  EXPECT_NEAR(r.scale_length, ScaleLength(4 * M_PI, 80), 0.02);  // a fine sphere's area
  EXPECT_EQ(r.num_sources, 64u);
  EXPECT_GT(r.num_pairs, 1000u);
  for (int b = 0; b < index::kAccuracyBins; ++b) {
    for (int k = 0; k < 2; ++k) EXPECT_GE(r.unfold_bound[k][b], 0);
    for (int k = 0; k < 4; ++k) EXPECT_GE(r.trace_bound[k][b], 0);
  }
  // Far O(1) answers err by more than nothing, and by less than the sphere.
  EXPECT_GT(r.unfold_bound[1][5], 0);
  EXPECT_LT(r.unfold_bound[1][5], 0.5);
  // The same input gives the same record (threads do not matter: one pass).
  index::IndexData again = IndexDataOf(m);
  ASSERT_TRUE(AddCalibration(m, again).ok());
  EXPECT_EQ(std::memcmp(&again.accuracy[0], &r, sizeof(r)), 0);
}

// A sequential calibration draws more sources while it is not settled, and
// the sources it adds are the ones a calibration of that many sources draws
// at once: the same record to the bit.
TEST(CalibrationTest, SequentialCalibrationAddsTheSourcesOfALargerOne) {
  const mesh::Mesh m = mesh::gen::Sphere(3, 1.0);
  CalibrationOptions options;
  options.pairs.num_sources = 24;
  options.pairs.threads = 2;
  index::IndexData at_once = IndexDataOf(m);
  ASSERT_TRUE(AddCalibration(m, at_once, options).ok());

  options.pairs.num_sources = 6;
  std::vector<int32_t> seen;
  index::IndexData grown = IndexDataOf(m);
  ASSERT_TRUE(AddCalibrationUntil(m, grown, options, 24,
                                  [&](const Calibration& c) {
                                    seen.push_back(static_cast<int32_t>(c.record.num_sources));
                                    return false;
                                  })
                  .ok());
  EXPECT_EQ(seen, (std::vector<int32_t>{6, 12}));  // 24 is the most: not asked again
  ASSERT_EQ(grown.accuracy.size(), 1u);
  EXPECT_EQ(grown.accuracy[0].num_sources, 24u);
  EXPECT_EQ(std::memcmp(&grown.accuracy[0], &at_once.accuracy[0], sizeof(index::AccuracyRecord)),
            0);
  EXPECT_EQ(std::memcmp(&grown.spread_bounds[0], &at_once.spread_bounds[0],
                        sizeof(index::SpreadBoundRecord)),
            0);

  // Settled at once: the first sources only.
  index::IndexData first = IndexDataOf(m);
  ASSERT_TRUE(
      AddCalibrationUntil(m, first, options, 24, [](const Calibration&) { return true; }).ok());
  EXPECT_EQ(first.accuracy[0].num_sources, 6u);
}

TEST(CalibrationTest, BoundsCoverHeldOutPairsOfAnotherSeed) {
  const mesh::Mesh m = mesh::gen::Sphere(4, 1.0);
  index::IndexData data = IndexDataOf(m);
  ASSERT_TRUE(AddCalibration(m, data).ok());
  auto index = index::Index::FromBytes(*index::SerializeIndex(data));
  ASSERT_TRUE(index.ok());
  auto engine = query::QueryEngine::Create(*index);
  ASSERT_TRUE(engine.ok());
  const auto pairs = DrawPairs(m, 80, {.num_sources = 10, .uniform_points = 80, .seed = 99});
  int covered = 0;
  for (const ExactPair& pair : pairs) {
    double bound = -1;
    const double d = *(*engine)->Distance(pair.p, pair.q, {}, nullptr, &bound);
    covered += std::abs(d - pair.exact) <= bound + 1e-9 * pair.exact;
  }
  EXPECT_GT(covered, 0.97 * pairs.size());
}

TEST(CalibrationTest, SpreadBoundsAreTighterWhereTheyCoverAsWell) {
  // On a torus (curved both ways), the per-pair bounds of O(1) answers beyond
  // 3L cover as the constant ones do, with a smaller median bound. A bin
  // keeps its constant bound (factor and epsilon 0) where the per-pair ones
  // would not be tighter; most bins do not.
  const mesh::Mesh m = mesh::gen::Torus(64, 32, 2.0, 0.7);
  index::IndexData data = IndexDataOf(m, 150);
  ASSERT_TRUE(AddCalibration(m, data).ok());
  ASSERT_EQ(data.spread_bounds.size(), 1u);
  int per_pair_bins = 0;
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < index::kAccuracyBins; ++b) {
      const float factor = data.spread_bounds[0].factor[k][b];
      const float epsilon = data.spread_bounds[0].epsilon[k][b];
      EXPECT_EQ(factor > 0, epsilon > 0) << k << " " << b;
      per_pair_bins += factor > 0;
    }
  }
  EXPECT_GT(per_pair_bins, index::kAccuracyBins);
  auto spread_index = index::Index::FromBytes(*index::SerializeIndex(data));
  data.spread_bounds.clear();
  auto constant_index = index::Index::FromBytes(*index::SerializeIndex(data));
  ASSERT_TRUE(spread_index.ok() && constant_index.ok());
  auto spread = query::QueryEngine::Create(*spread_index);
  auto constant = query::QueryEngine::Create(*constant_index);
  ASSERT_TRUE(spread.ok() && constant.ok());
  const auto pairs = DrawPairs(m, 150, {.num_sources = 12, .uniform_points = 100, .seed = 99});
  const query::DistanceOptions pure{.near_pairs = query::NearPairs::kUnfold};
  std::vector<double> spread_bounds, constant_bounds;
  int spread_covered = 0, constant_covered = 0;
  for (const ExactPair& pair : pairs) {
    if (pair.bin < 2) continue;  // beyond 3L: O(1) answers
    double b1 = -1, b2 = -1;
    const double d = *(*spread)->Distance(pair.p, pair.q, pure, nullptr, &b1);
    EXPECT_EQ(*(*constant)->Distance(pair.p, pair.q, pure, nullptr, &b2), d);
    spread_covered += std::abs(d - pair.exact) <= b1;
    constant_covered += std::abs(d - pair.exact) <= b2;
    spread_bounds.push_back(b1);
    constant_bounds.push_back(b2);
  }
  ASSERT_GT(spread_bounds.size(), 500u);
  // The batch gives every pair the same answer and bound as one at a time.
  std::vector<mesh::SurfacePoint> from, to;
  for (const ExactPair& pair : pairs) {
    from.push_back(pair.p);
    to.push_back(pair.q);
  }
  std::vector<double> out(pairs.size()), bounds(pairs.size());
  ASSERT_TRUE((*spread)->DistanceBatch(from, to, out, {}, nullptr, bounds).ok());
  for (size_t k = 0; k < pairs.size(); ++k) {
    double bound = -1;
    EXPECT_EQ(*(*spread)->Distance(from[k], to[k], {}, nullptr, &bound), out[k]);
    EXPECT_EQ(bound, bounds[k]);
  }
  const double n = static_cast<double>(spread_bounds.size());
  EXPECT_GT(spread_covered, 0.97 * n);
  EXPECT_GT(constant_covered, 0.97 * n);
  auto median = [](std::vector<double> x) {
    std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
    return x[x.size() / 2];
  };
  EXPECT_LT(median(spread_bounds), median(constant_bounds));
}

TEST(CalibrationTest, PairsDoNotDependOnTheThreadCount) {
  const mesh::Mesh m = mesh::gen::Torus(24, 12, 1.0, 0.4);
  PairOptions options{.num_sources = 7, .uniform_points = 20, .per_bin_points = 5, .seed = 5};
  const auto one = DrawPairs(m, 300, options);
  options.threads = 3;
  const auto three = DrawPairs(m, 300, options);
  ASSERT_EQ(one.size(), three.size());
  // Both kinds of source and every bin are drawn.
  int vertex_pairs = 0, bins[kNumScaleBins] = {};
  for (size_t k = 0; k < one.size(); ++k) {
    const ExactPair &a = one[k], &b = three[k];
    EXPECT_EQ(a.p.face, b.p.face);
    EXPECT_EQ(a.q.face, b.q.face);
    EXPECT_EQ(a.p.w, b.p.w);
    EXPECT_EQ(a.q.w, b.q.w);
    EXPECT_EQ(a.exact, b.exact);
    EXPECT_EQ(a.bin, b.bin);
    vertex_pairs += a.vertices;
    ++bins[a.bin];
  }
  EXPECT_GT(vertex_pairs, 0);
  EXPECT_LT(vertex_pairs, static_cast<int>(one.size()));
  for (int b = 0; b < kNumScaleBins; ++b) EXPECT_GT(bins[b], 0) << ScaleBinName(b);
  // Another seed draws other pairs.
  options.seed = 6;
  const auto other = DrawPairs(m, 300, options);
  ASSERT_FALSE(other.empty());
  EXPECT_NE(other[0].exact, one[0].exact);
}

// A coarse sphere (42 vertices) sampled more finely than it has vertices:
// the builder splits its long edges, and the held-out pairs are drawn and
// propagated on the 42-vertex mesh. Their exact distances must be the split
// mesh's, their points internal ones, their vertex pairs the file's vertices.
TEST(CalibrationTest, PairsOfASplitIndexAreDrawnBeforeTheSplitWithTheSameDistances) {
  const mesh::Mesh coarse = mesh::gen::Sphere(1, 1.0);
  auto prepared = builder::PrepareMesh(coarse, builder::RecordRepair(mesh::WithoutRepairs(coarse)),
                                       120, /*refine=*/true);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  ASSERT_GT(prepared->mesh.num_vertices(), 3 * coarse.num_vertices());
  builder::BuildOptions options;
  options.num_samples = 120;
  options.threads = 2;
  builder::BuildSummary summary;
  auto data = builder::BuildPreparedIndex(*prepared, options, &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  auto index = index::Index::FromBytes(*index::SerializeIndex(*data));
  ASSERT_TRUE(index.ok()) << index.status();
  ASSERT_EQ((*index)->num_vertices() - (*index)->split_vertices(), coarse.num_vertices());

  const mesh::Mesh& split = prepared->mesh;
  auto pairs = HeldOutPairs(split, **index,
                            {.num_sources = 6, .uniform_points = 20, .per_bin_points = 5, .seed = 5});
  ASSERT_TRUE(pairs.ok()) << pairs.status();
  ASSERT_GT(pairs->size(), 100u);
  geodesic::VertexGeodesicSolver solver(split);
  int vertex_pairs = 0;
  for (int32_t s = 0; s < 6; ++s) {
    std::vector<mesh::SurfacePoint> targets;
    std::vector<const ExactPair*> of_source;
    for (const ExactPair& pair : *pairs) {
      if (pair.source != s) continue;
      for (const mesh::SurfacePoint& x : {pair.p, pair.q}) {
        ASSERT_GE(x.face, 0);
        ASSERT_LT(x.face, split.num_faces());
        EXPECT_NEAR(x.w[0] + x.w[1] + x.w[2], 1.0, 1e-12);
      }
      if (pair.vertices) {
        ++vertex_pairs;
        // At a corner of the file's mesh: one weight 1, on a vertex below the split's.
        for (const mesh::SurfacePoint& x : {pair.p, pair.q}) {
          const int corner = static_cast<int>(std::max_element(x.w.begin(), x.w.end()) - x.w.begin());
          EXPECT_EQ(x.w[corner], 1.0);
          EXPECT_LT(split.face(x.face)[corner], coarse.num_vertices());
        }
      }
      targets.push_back(pair.q);
      of_source.push_back(&pair);
    }
    if (targets.empty()) continue;
    geodesic::VertexGeodesicOptions exact;
    exact.targets = targets;
    ASSERT_TRUE(solver.Propagate({of_source[0]->p}, exact).ok());
    for (size_t k = 0; k < targets.size(); ++k) {
      EXPECT_NEAR(solver.TargetDistance(k), of_source[k]->exact, 1e-9 + 1e-7 * of_source[k]->exact)
          << "source " << s << ", pair " << k;
    }
  }
  EXPECT_GT(vertex_pairs, 0);
}

TEST(CalibrationTest, RefusesAnIndexOfAnotherMesh) {
  const mesh::Mesh m = mesh::gen::Sphere(4, 1.0);
  index::IndexData data = IndexDataOf(m);
  auto index = index::Index::FromBytes(*index::SerializeIndex(data));
  ASSERT_TRUE(index.ok());
  EXPECT_EQ(Calibrate(mesh::gen::Sphere(3, 1.0), *index).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace geodex::validation

namespace geodex::validation {
namespace {

// The figures a target-error build judges: every bin of both kinds has
// pairs on a sphere of 200 samples (its half circumference is about 11.7L),
// and each p99's upper confidence limit is at least the p99.
TEST(CalibrationTest, BinFiguresOfBothKindsWithUpperLimits) {
  const mesh::Mesh m = mesh::gen::Sphere(4, 1.0);
  index::IndexData data = IndexDataOf(m, 200);
  Calibration calibration;
  ASSERT_TRUE(AddCalibration(m, data, {}, &calibration).ok());
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < kNumScaleBins; ++b) {
      EXPECT_GE(calibration.bins.pairs[k][b], 64 / 2 * 10) << k << " " << b;
      EXPECT_GE(calibration.bins.p99_upper[k][b], calibration.bins.p99[k][b]) << k << " " << b;
    }
    // Far pairs err by something, near pairs (traced) much less.
    EXPECT_GT(calibration.bins.p99[k][3], 0) << k;
    EXPECT_LT(calibration.bins.p99[k][0], calibration.bins.p99[k][3]) << k;
  }
  EXPECT_NEAR(calibration.record.uniform_rms, data.accuracy[0].uniform_rms, 0);
  EXPECT_GE(calibration.confidence.rms_upper, calibration.record.uniform_rms);
}

TEST(UniformConfidenceTest, SourcesThatAgreeLeaveNoMarginAndOneBadSourceWidensIt) {
  // Ten sources, four pairs each, every source with relative errors +-0.01:
  // the sources' mean squared errors agree, so the limit is the RMS itself.
  std::vector<double> errors;
  std::vector<int32_t> source;
  for (int32_t s = 0; s < 10; ++s) {
    for (double e : {0.01, -0.01, 0.01, -0.01}) {
      errors.push_back(e);
      source.push_back(s);
    }
  }
  EXPECT_NEAR(UniformConfidenceOf(errors, source, {}).rms_upper, 0.01, 1e-12);
  // One source errs 0.05 on every pair: mean squared error
  // (9 * 1e-4 + 25e-4) / 10 = 3.4e-4, sample standard deviation of the
  // sources' 1e-4 (x9) and 25e-4 (x1) = 7.589e-4, standard error 2.4e-4.
  for (size_t k = 0; k < 4; ++k) errors[k] = 0.05;
  const double mean = 3.4e-4;
  const double se = std::sqrt((9 * 2.4e-4 * 2.4e-4 + 21.6e-4 * 21.6e-4) / 9 / 10);
  EXPECT_NEAR(UniformConfidenceOf(errors, source, {}).rms_upper, std::sqrt(mean + 1.645 * se),
              1e-12);
  EXPECT_GT(std::sqrt(mean + 1.645 * se), std::sqrt(mean) * 1.3);
}

TEST(UniformConfidenceTest, FarP99LimitIsAHigherOrderStatistic) {
  // 1000 errors 0.001 .. 1.000: the 99th percentile is about 0.990; with
  // 95% confidence it is below the ceil(990 + 1.645 sqrt(9.9)) = 996th
  // order statistic (0-based), 0.997.
  std::vector<double> far;
  for (int k = 1000; k >= 1; --k) far.push_back(k / 1000.0);
  EXPECT_DOUBLE_EQ(UniformConfidenceOf({}, {}, far).far_p99_upper, 0.997);
  EXPECT_EQ(UniformConfidenceOf({}, {}, {}).far_p99_upper, 0);
  // Few pairs: the largest.
  EXPECT_DOUBLE_EQ(UniformConfidenceOf({}, {}, {0.1, 0.3, 0.2}).far_p99_upper, 0.3);
}

TEST(UniformConfidenceTest, P99UpperLimitIsTheOrderStatisticOfAnyErrors) {
  std::vector<double> x;
  for (int k = 1; k <= 1000; ++k) x.push_back(k / 1000.0);
  EXPECT_DOUBLE_EQ(P99UpperLimit(x), 0.997);
  EXPECT_EQ(P99UpperLimit({}), 0);
}

}  // namespace
}  // namespace geodex::validation
