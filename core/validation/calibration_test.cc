#include "core/validation/calibration.h"

#include "core/builder/builder.h"
#include "core/mesh/generators.h"
#include "core/query/query_engine.h"
#include "core/validation/target_error.h"
#include "gtest/gtest.h"

namespace geodex::validation {
namespace {

index::IndexData BuildSphere(const mesh::Mesh& m) {
  builder::BuildOptions options;
  options.num_samples = 80;
  options.threads = 2;
  builder::BuildSummary summary;
  auto data = builder::BuildIndex(m, options, &summary);
  EXPECT_TRUE(data.ok()) << data.status();
  return *std::move(data);
}

TEST(CalibrationTest, BoundsAreSaneAndDeterministic) {
  const mesh::Mesh m = mesh::gen::Sphere(4, 1.0);
  index::IndexData data = BuildSphere(m);
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
  index::IndexData again = BuildSphere(m);
  ASSERT_TRUE(AddCalibration(m, again).ok());
  EXPECT_EQ(std::memcmp(&again.accuracy[0], &r, sizeof(r)), 0);
}

TEST(CalibrationTest, BoundsCoverHeldOutPairsOfAnotherSeed) {
  const mesh::Mesh m = mesh::gen::Sphere(4, 1.0);
  index::IndexData data = BuildSphere(m);
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

TEST(CalibrationTest, RefusesAnIndexOfAnotherMesh) {
  const mesh::Mesh m = mesh::gen::Sphere(4, 1.0);
  index::IndexData data = BuildSphere(m);
  auto index = index::Index::FromBytes(*index::SerializeIndex(data));
  ASSERT_TRUE(index.ok());
  EXPECT_EQ(Calibrate(mesh::gen::Sphere(3, 1.0), *index).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace geodex::validation

namespace geodex::validation {
namespace {

TEST(TargetErrorTest, GrowsTheSamplesUntilTheTargetIsMet) {
  // The default answer traces pairs that may be closer than 3L; start where
  // 3L is well below the sphere's half circumference (with 20 samples every
  // pair is traced and the first round already meets the target).
  const mesh::Mesh m = mesh::gen::Sphere(3, 1.0);
  builder::BuildOptions build;
  build.num_samples = 60;
  build.threads = 2;
  TargetErrorOptions options;
  options.target_rms = 0.011;
  auto result = BuildForTargetError(m, build, options);
  ASSERT_TRUE(result.ok()) << result.status();
  ASSERT_TRUE(result->reached);
  ASSERT_GE(result->rounds.size(), 2u);  // 60 samples are not enough
  EXPECT_LE(result->rounds.back().rms, 0.011);
  EXPECT_GT(result->rounds.front().rms, 0.011);
  ASSERT_EQ(result->data.accuracy.size(), 1u);
  EXPECT_EQ(result->data.samples.size(), static_cast<size_t>(result->rounds.back().samples));
  for (size_t k = 1; k < result->rounds.size(); ++k) {
    EXPECT_GT(result->rounds[k].samples, result->rounds[k - 1].samples);
  }
}

TEST(TargetErrorTest, StopsAtTheCapAndSaysSo) {
  const mesh::Mesh m = mesh::gen::Sphere(3, 1.0);
  builder::BuildOptions build;
  build.num_samples = 20;
  TargetErrorOptions options;
  options.target_rms = 1e-6;
  options.max_samples = 30;
  auto result = BuildForTargetError(m, build, options);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_FALSE(result->reached);
  EXPECT_EQ(result->rounds.size(), 2u);  // 20, then 30
  options.target_rms = -1;
  EXPECT_EQ(BuildForTargetError(m, build, options).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace geodex::validation
