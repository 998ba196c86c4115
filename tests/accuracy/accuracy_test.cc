// CI-sized accuracy run on generated shapes, by distance scale: fails when a
// bin regresses, when the refinement of close pairs stops paying, when error
// bounds stop covering, or when a tolerance is not met.

#include "tests/accuracy/accuracy.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <utility>

#include "core/mesh/generators.h"
#include "core/mesh/mesh_repair.h"
#include "core/build/build_testing.h"
#include "gtest/gtest.h"

namespace geodex::accuracy {
namespace {

namespace gen = mesh::gen;

struct Measured {
  ModeReport unfold, by_default, tolerance;
  PathReport paths;
};

// `matrix`: the builder's 24-bit codes, or kFull where a test checks the
// method to float precision.
Measured Measure(const mesh::Mesh& m, int32_t samples,
                 index::MatrixLayout matrix = index::MatrixLayout::kCoded) {
  const std::shared_ptr<const query::QueryEngine> engine =
      geodex::testing::TestEngineOrThrow(m, samples, /*calibrate=*/true, {}, matrix);
  const index::Index* index = &engine->index();
  const auto pairs = validation::DrawPairs(
      m, index->num_samples(),
      {.num_sources = 8, .uniform_points = 100, .per_bin_points = 30, .seed = 7});
  auto mode = [&](query::DistanceOptions options) {
    return Evaluate(pairs, [&](const mesh::SurfacePoint& p, const mesh::SurfacePoint& q) {
      Answer a;
      a.distance = *engine->Distance(p, q, options, nullptr, &a.bound);
      return a;
    });
  };
  Measured r;
  r.unfold = mode({.near_pairs = query::NearPairs::kUnfold});
  r.by_default = mode({});
  r.tolerance = mode({.tolerance = 0.005});
  r.paths = MeasurePaths(m, *engine, 4, 15, 3);
  const std::string label = m.name() + " m=" + std::to_string(index->num_samples());
  std::printf("%s%s%s%s", MarkdownHeader().c_str(),
              MarkdownRows(label + " unfold", r.unfold).c_str(),
              MarkdownRows(label + " default", r.by_default).c_str(),
              MarkdownRows(label + " tol0.005", r.tolerance).c_str());
  std::printf("path/exact p99 %.5f, traced %.5f\n", 1 + r.paths.path.p99, 1 + r.paths.traced.p99);
  return r;
}

// A bin's p99 limit meaning "the shape holds no pair at this distance": the
// check is then that none was drawn there.
constexpr double kNoPairs = -1;
// A bin with fewer pairs than this is not checked by its p99: the check fails
// instead of passing a bin nobody looked at.
constexpr int64_t kMinPairs = 20;

// Per bin, the p99 limits of vertex pairs and of interior pairs; kNoPairs
// where the bin must be empty.
struct BinLimits {
  double vertex[kNumBins];
  double interior[kNumBins];
};

// Every bin of `r` holds at least kMinPairs pairs (or none, where its limit
// is kNoPairs), its p99 stays below its limit, and its bounds cover at least
// `coverage` of its pairs.
void ExpectBins(const ModeReport& r, const BinLimits& limits, double coverage,
                const std::string& what) {
  for (int b = 0; b < kNumBins; ++b) {
    for (int kind = 0; kind < 2; ++kind) {
      const BinReport& bin = kind == 0 ? r.vertex[b] : r.interior[b];
      const double limit = kind == 0 ? limits.vertex[b] : limits.interior[b];
      const std::string where = what + (kind == 0 ? " vertex " : " interior ") + BinName(b);
      if (limit == kNoPairs) {
        EXPECT_EQ(bin.error.count, 0)
            << where << ": pairs where none was expected; measure the bin and give it a limit";
        continue;
      }
      EXPECT_GE(bin.error.count, kMinPairs) << where << ": too few pairs to check";
      EXPECT_LT(bin.error.p99, limit) << where;
      EXPECT_GE(bin.coverage, coverage) << where;
    }
  }
}

// The same limit for every bin that holds pairs (a promise, such as a
// tolerance), kNoPairs for the others.
BinLimits Uniform(double limit, std::initializer_list<int> empty_bins = {}) {
  BinLimits out;
  for (int b = 0; b < kNumBins; ++b) out.vertex[b] = out.interior[b] = limit;
  for (int b : empty_bins) out.vertex[b] = out.interior[b] = kNoPairs;
  return out;
}

TEST(AccuracyTest, DevelopableSurfacesAreExact) {
  // m=120 on the finer sheet once gave a 25.7% error: a point beside the
  // triangle unfolded to the wrong side of an edge.
  const std::pair<mesh::Mesh, int32_t> cases[] = {{gen::FoldedSheet(32, 20, 2.0, 1.0, 1.1), 60},
                                                  {gen::FoldedSheet(40, 24, 2.0, 1.0, 1.1), 120}};
  for (const auto& [m, samples] : cases) {
    // Exact to the float32 matrix's rounding.
    const Measured r = Measure(m, samples, index::MatrixLayout::kFull);
    for (const ModeReport* mode : {&r.unfold, &r.by_default}) {
      for (int b = 0; b < kNumBins; ++b) {
        EXPECT_LT(mode->vertex[b].error.max, 1e-5) << BinName(b);
        EXPECT_LT(mode->interior[b].error.max, 1e-5) << BinName(b);
      }
    }
    EXPECT_GT(r.by_default.interior[0].error.count, 100);
  }
}

// Regression guards. Each limit is a figure measured when it was set, times
// 1.5 (so that a 2x regression fails), and at least 1e-5 where the measured
// p99 is 0 to rounding; a coverage limit lets the uncovered share grow 1.5x
// (at least to 1%). The figures and the command that prints them:
// tests/bench/accuracy.md, "The CI accuracy guard's limits".
constexpr double kExact = 1e-5;

TEST(AccuracyTest, Sphere) {
  // m = 200 puts 10L (2.69) under half the unit sphere's circumference (pi),
  // so every bin holds pairs.
  const Measured r = Measure(gen::Sphere(4, 1.0), 200);
  // Measured p99, vertex / interior: 0 / 0, 0 / 0, 1.128% / 1.274%, 3.329% /
  // 4.150%; coverage from 96.48%.
  ExpectBins(r.by_default, {{kExact, kExact, 0.0169, 0.050}, {kExact, kExact, 0.0191, 0.0623}},
             0.947, "default");
  // Coverage from 99.30%.
  ExpectBins(r.tolerance, Uniform(0.005), 0.989, "tolerance");
  // Close pairs: refining pays.
  EXPECT_LT(r.by_default.interior[0].error.p99, 0.5 * r.unfold.interior[0].error.p99);
  // Measured: path / exact p99 1.00025.
  EXPECT_GE(r.paths.path.count, kMinPairs);
  EXPECT_LT(r.paths.path.p99, 0.000375);
}

TEST(AccuracyTest, Torus) {
  // m = 120 tiles this torus coarsely: its farthest pairs are under 10L.
  const Measured r = Measure(gen::Torus(64, 32, 2.0, 0.7), 120);
  // Measured p99, vertex / interior: 0 / 0, 0.651% / 0.007%, 9.711% /
  // 6.901% (the O(1) answer: 6.9% / 4.2%, 14.6% / 11.7%, 11.0% / 9.1%);
  // coverage from 98.54%.
  ExpectBins(r.by_default,
             {{kExact, 0.00977, 0.146, kNoPairs}, {kExact, 0.000105, 0.1035, kNoPairs}}, 0.978,
             "default");
  // Coverage from 99.10%.
  ExpectBins(r.tolerance, Uniform(0.005, {3}), 0.986, "tolerance");
  EXPECT_LT(r.by_default.interior[1].error.p99, 0.5 * r.unfold.interior[1].error.p99);
  // Measured: path / exact p99 1.01183.
  EXPECT_GE(r.paths.path.count, kMinPairs);
  EXPECT_LT(r.paths.path.p99, 0.0178);
}

// The development meshes, where present: one scanned mesh guards what the
// generated shapes cannot (uneven triangles, features, near pairs that wrap
// round vertices).
std::string SharedMeshDir() {
  const char* env = std::getenv("GEODEX_SHARED_MESHES");
  return env != nullptr ? env : GEODEX_SHARED_MESHES_DEFAULT;
}

TEST(AccuracyTest, SharedMesh) {
  const std::string path = SharedMeshDir() + "/bunny_3k.obj";
  if (!std::filesystem::exists(path)) {
    GTEST_SKIP() << "SKIPPED: no " << path
                 << " (the development meshes; set GEODEX_SHARED_MESHES): the accuracy guard "
                    "on a shared mesh did not run";
  }
  absl::StatusOr<mesh::RepairedMesh> repaired = mesh::LoadAndRepairMesh(path);
  ASSERT_TRUE(repaired.ok()) << repaired.status();
  ASSERT_FALSE(repaired->report.changed()) << repaired->report.Summary();
  const Measured r = Measure(repaired->mesh, 300);
  // Measured p99, vertex / interior: 0 / 0.048%, 0.061% / 2.302%, 3.641% /
  // 3.865%, 4.119% / 4.186%; coverage from 97.99%.
  ExpectBins(r.by_default, {{kExact, 0.000915, 0.0546, 0.0618}, {0.00072, 0.0345, 0.058, 0.0628}},
             0.969, "default");
  // Coverage from 99.33%.
  ExpectBins(r.tolerance, Uniform(0.005), 0.989, "tolerance");
  // Measured: path / exact p99 1.01619.
  EXPECT_GE(r.paths.path.count, kMinPairs);
  EXPECT_LT(r.paths.path.p99, 0.0243);
}

}  // namespace
}  // namespace geodex::accuracy
