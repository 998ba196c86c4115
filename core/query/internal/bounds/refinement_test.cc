#include "core/query/internal/bounds/refinement.h"

#include <cmath>

#include "core/mesh/generators.h"
#include "core/query/internal/query_parts_testing.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

struct RefinerFixture {
  explicit RefinerFixture(const mesh::Mesh& mesh, int32_t samples, double refine_below)
      : parts(mesh, samples),
        bounds(*parts.index),
        refiner(parts.view, parts.unfolding, bounds, parts.paths, parts.exact, /*walk=*/true,
                refine_below) {}
  testing::QueryParts parts;
  ErrorBounds bounds;
  Refiner refiner;
};

TEST(RefinerTest, WhatIsRefinedFollowsTheOptions) {
  const RefinerFixture f(mesh::gen::Sphere(2, 1.0), 30, /*refine_below=*/0.5);
  const DistanceOptions path, unfold{.near_pairs = NearPairs::kUnfold};
  EXPECT_TRUE(f.refiner.Needs(path, false, /*near=*/true, 2.0));  // near pairs always
  EXPECT_TRUE(f.refiner.Needs(path, false, false, 0.4));          // below refine_below
  EXPECT_FALSE(f.refiner.Needs(path, false, false, 0.6));
  EXPECT_FALSE(f.refiner.Needs(unfold, false, false, 0.4));  // pure O(1)
  EXPECT_TRUE(f.refiner.Needs(unfold, /*bounds=*/true, false, 0.6));
  EXPECT_TRUE(f.refiner.Needs({.tolerance = 0.01}, false, false, 0.6));
}

TEST(RefinerTest, RefinedNearPairsOnAFoldAreExactAndSymmetric) {
  const mesh::Mesh flat = mesh::gen::Grid(10, 10, 2, 2);
  // Every pair closer than 10 is refined: all of these.
  const RefinerFixture f(mesh::gen::FoldedSheet(10, 10, 2, 2, 2.0), 20, /*refine_below=*/10);
  const MeshView& view = f.parts.view;
  for (const NearPairs mode : {NearPairs::kPath, NearPairs::kExact}) {
    for (int32_t i = 0; i + 23 < 200; i += 13) {
      const SurfacePoint p = view.Canonical({i, {0.2, 0.3, 0.5}});
      const SurfacePoint q = view.Canonical({i + 23, {0.5, 0.25, 0.25}});
      const LiftedPoint lp = f.parts.lifting.Lift(p), lq = f.parts.lifting.Lift(q);
      const double unfolded = f.parts.unfolding.Distance(lp, lq);
      const bool near = f.parts.unfolding.AreNear(lp, lq);
      const DistanceOptions options{.near_pairs = mode};
      const double d = f.refiner.Refine(p, q, lp, lq, unfolded, near, options, nullptr, nullptr);
      const double back = f.refiner.Refine(q, p, lq, lp, unfolded, near, options, nullptr, nullptr);
      const double want = (mesh::PositionOf(flat, p) - mesh::PositionOf(flat, q)).norm();
      EXPECT_NEAR(d, want, 1e-9) << "pair " << i;
      EXPECT_EQ(d, back);
    }
  }
}

TEST(RefinerTest, BoundIsNaNWithoutCalibration) {
  const RefinerFixture f(mesh::gen::Sphere(2, 1.0), 30, 0.5);
  const SurfacePoint p{0, {0.2, 0.3, 0.5}}, q{1, {0.2, 0.3, 0.5}};
  const LiftedPoint lp = f.parts.lifting.Lift(p), lq = f.parts.lifting.Lift(q);
  double bound = 0;
  f.refiner.Refine(p, q, lp, lq, f.parts.unfolding.Distance(lp, lq), true, {}, nullptr, &bound);
  EXPECT_TRUE(std::isnan(bound));
}

}  // namespace
}  // namespace geodex::query
