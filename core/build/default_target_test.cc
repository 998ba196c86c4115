// The default build (no sample count: the default error target) of
// generated curved surfaces, measured independently: other sources and
// another seed than the build's validation, exact distances from the exact
// engine. The default answer meets the target (target_error.h): relative
// RMS <= E over area-uniform interior pairs, p99 <= 4E over the uniform
// pairs at least 8 L1000 apart, vertex and interior pairs apart; the index
// is under the default budget; and in every bin the bounds are fitted in
// they cover at least 99% of the pairs.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/build/build_rounds.h"
#include "core/mesh/generators.h"
#include "core/query/engine/query_engine.h"
#include "core/validation/pair_sampling.h"
#include "core/validation/target_error.h"
#include "gtest/gtest.h"

namespace geodex::builder {
namespace {

// A sphere with bumps: radius 1 + 0.08 sin(4 theta) sin(3 phi), so the
// curvature changes sign across the surface.
mesh::Mesh BumpySphere() {
  const mesh::Mesh sphere = mesh::gen::Sphere(4, 1.0);
  std::vector<mesh::Vec3> positions = sphere.positions();
  for (mesh::Vec3& p : positions) {
    const double theta = std::atan2(p.y(), p.x());
    const double phi = std::acos(std::clamp(p.z() / p.norm(), -1.0, 1.0));
    p *= (1 + 0.08 * std::sin(4 * theta) * std::sin(3 * phi)) / p.norm();
  }
  absl::StatusOr<mesh::Mesh> bumpy = mesh::Mesh::Create(
      std::move(positions), std::vector<mesh::Triangle>(sphere.faces()), "bumpy-sphere");
  EXPECT_TRUE(bumpy.ok()) << bumpy.status();
  return *std::move(bumpy);
}

double Quantile(std::vector<double> x, double q) {
  std::sort(x.begin(), x.end());
  return x[std::min(x.size() - 1, static_cast<size_t>(q * x.size()))];
}

void ExpectDefaultTargetMet(const mesh::Mesh& coarse) {
  SCOPED_TRACE(coarse.name());
  RoundsOptions options;
  options.build.num_samples = kDefaultFirstRoundSamples;
  options.build.threads = 2;
  absl::StatusOr<TargetBuild> build = BuildToTarget(coarse, {}, options, nullptr);
  ASSERT_TRUE(build.ok()) << build.status();
  ASSERT_TRUE(build->last.reached) << build->data.report;
  absl::StatusOr<std::string> bytes = index::SerializeIndex(build->data);
  ASSERT_TRUE(bytes.ok());
  const size_t bytes_size = bytes->size();
  absl::StatusOr<std::shared_ptr<const index::Index>> index =
      index::Index::FromBytes(*std::move(bytes));
  ASSERT_TRUE(index.ok()) << index.status();
  absl::StatusOr<std::shared_ptr<const query::QueryEngine>> engine =
      query::QueryEngine::Create(*index);
  ASSERT_TRUE(engine.ok()) << engine.status();

  // Another seed than the calibration's, and vertex pairs among the
  // generated mesh's vertices (not the split's midpoints).
  validation::PairOptions pair_options;
  pair_options.num_sources = 40;
  pair_options.uniform_points = 100;
  pair_options.per_bin_points = 30;
  pair_options.seed = 20240613;
  pair_options.threads = 2;
  pair_options.vertex_limit = coarse.num_vertices();
  const std::vector<validation::ExactPair> pairs =
      validation::DrawPairs(build->mesh, (*index)->num_samples(), pair_options);
  const double unit = validation::ScaleLength(coarse.TotalArea(), validation::kFixedUnitSamples);
  std::vector<double> far[2], uniform;
  // Coverage by the bins the bounds are fitted in (the index's own L).
  int64_t covered[2][validation::kNumScaleBins] = {}, pairs_in[2][validation::kNumScaleBins] = {};
  for (const validation::ExactPair& pair : pairs) {
    double bound = 0;
    const absl::StatusOr<double> d = (*engine)->Distance(pair.p, pair.q, {}, nullptr, &bound);
    ASSERT_TRUE(d.ok()) << d.status();
    const int kind =
        pair.vertices ? validation::BinConfidence::kVertex : validation::BinConfidence::kInterior;
    const double relative = (*d - pair.exact) / pair.exact;
    if (pair.uniform && pair.exact >= 8 * unit) far[kind].push_back(std::abs(relative));
    if (pair.uniform && !pair.vertices) uniform.push_back(relative);
    covered[kind][pair.bin] += std::abs(*d - pair.exact) <= bound + 1e-12 * pair.exact;
    ++pairs_in[kind][pair.bin];
  }
  double sum = 0;
  for (double e : uniform) sum += e * e;
  const double target = validation::kDefaultTargetError;
  EXPECT_LE(std::sqrt(sum / uniform.size()), validation::TargetLimit(0, target)) << "uniform RMS";
  for (int kind = 0; kind < 2; ++kind) {
    const std::string name = validation::TargetCheckName(1 + kind);
    ASSERT_GE(far[kind].size(), 200u) << name;
    EXPECT_LE(Quantile(far[kind], 0.99), validation::TargetLimit(1 + kind, target)) << name;
  }
  for (int kind = 0; kind < 2; ++kind) {
    for (int bin = 0; bin < validation::kNumScaleBins; ++bin) {
      if (pairs_in[kind][bin] < 100) continue;  // too few for a 1% tail
      EXPECT_GE(static_cast<double>(covered[kind][bin]) / pairs_in[kind][bin], 0.99)
          << (kind == 0 ? "vertex " : "interior ") << bin << ": coverage of the bounds";
    }
  }
  // Under the default budget, with the sections written as predicted.
  EXPECT_LE(static_cast<int64_t>(bytes_size), validation::kMaxIndexBytes);
}

TEST(DefaultTargetTest, Sphere) { ExpectDefaultTargetMet(mesh::gen::Sphere(4, 1.0)); }

TEST(DefaultTargetTest, Torus) { ExpectDefaultTargetMet(mesh::gen::Torus(64, 32, 2.0, 0.7)); }

TEST(DefaultTargetTest, BumpySphere) { ExpectDefaultTargetMet(BumpySphere()); }

}  // namespace
}  // namespace geodex::builder
