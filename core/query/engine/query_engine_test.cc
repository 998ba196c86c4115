#include "core/query/engine/query_engine.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/builder/builder.h"
#include "core/mesh/generators.h"
#include "core/build/build_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

namespace gen = mesh::gen;
using mesh::Mesh;
using ::testing::HasSubstr;

std::shared_ptr<const QueryEngine> MakeEngine(
    const Mesh& m, int32_t samples, QueryOptions options = {},
    index::MatrixLayout matrix = index::MatrixLayout::kCoded) {
  return geodex::testing::TestEngineOrThrow(m, samples, /*calibrate=*/false, options, matrix);
}

// Area-uniform random surface points.
std::vector<SurfacePoint> RandomPoints(const Mesh& m, int count, uint32_t seed) {
  std::vector<double> cumulative(m.num_faces());
  double total = 0;
  for (int32_t f = 0; f < m.num_faces(); ++f) cumulative[f] = total += m.Area(f);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<SurfacePoint> out;
  for (int k = 0; k < count; ++k) {
    const int32_t f = static_cast<int32_t>(
        std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total) -
        cumulative.begin());
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    out.push_back({std::min(f, m.num_faces() - 1), {a, b, 1 - a - b}});
  }
  return out;
}

double Exact(const Mesh& m, const SurfacePoint& p, const SurfacePoint& q) {
  geodesic::ExactGeodesicSolver solver(m);
  EXPECT_TRUE(solver.Propagate({p}).ok());
  return solver.DistanceAt(q);
}

// Half of a cylinder (angle in [0, pi]): developable and simply connected.
Mesh HalfCylinder(int n_around, int n_along, double radius, double length) {
  std::vector<mesh::Vec3> positions;
  std::vector<mesh::Triangle> faces;
  for (int j = 0; j <= n_along; ++j) {
    for (int k = 0; k <= n_around; ++k) {
      const double angle = M_PI * k / n_around;
      positions.push_back(
          {radius * std::cos(angle), radius * std::sin(angle), length * j / n_along});
    }
  }
  auto id = [&](int k, int j) { return j * (n_around + 1) + k; };
  for (int j = 0; j < n_along; ++j) {
    for (int k = 0; k < n_around; ++k) {
      faces.push_back({id(k, j), id(k + 1, j), id(k + 1, j + 1)});
      faces.push_back({id(k, j), id(k + 1, j + 1), id(k, j + 1)});
    }
  }
  return *Mesh::Create(positions, faces, "half_cylinder");
}

double MaxRelativeError(const Mesh& m, const QueryEngine& engine, int num_points,
                        const DistanceOptions& options = {}) {
  const auto points = RandomPoints(m, num_points, 11);
  double max_rel = 0;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    geodesic::ExactGeodesicSolver solver(m);
    EXPECT_TRUE(solver.Propagate({points[i]}).ok());
    for (size_t j = 0; j < points.size(); j += 3) {
      const double exact = solver.DistanceAt(points[j]);
      if (exact < 1e-3) continue;
      const double approx = *engine.Distance(points[i], points[j], options);
      max_rel = std::max(max_rel, std::abs(approx - exact) / exact);
    }
  }
  return max_rel;
}

// The unfolding is exact on developable, simply connected surfaces: only the
// storage of the sample distances limits it. float32 rounds 6e-8 of a
// distance; the default 24-bit codes up to 4.8e-7 (index/sample_matrix.h),
// which the unfolding amplifies where a far sample lies near the line of an
// edge it is placed from (tests/bench/accuracy.md).
TEST(QueryEngineTest, DevelopableSurfacesAreExactToTheMatrixPrecision) {
  for (const Mesh& m : {gen::FoldedSheet(24, 16, 2.0, 1.0, 1.1), HalfCylinder(24, 16, 1.0, 3.0)}) {
    SCOPED_TRACE(m.name());
    EXPECT_LT(MaxRelativeError(m, *MakeEngine(m, 40, {}, index::MatrixLayout::kFull), 60), 1e-5);
    EXPECT_LT(MaxRelativeError(m, *MakeEngine(m, 40), 60), 5e-3);
  }
}

TEST(QueryEngineTest, UnfoldingSpreadVanishesWhereBothOrdersAreExact) {
  // On a developable sheet both orders of case 3.2 are exact; on a sphere
  // they disagree, symmetrically, and never between points of one
  // geodesic triangle.
  const Mesh sheet = gen::FoldedSheet(24, 16, 2.0, 1.0, 1.1);
  auto flat = MakeEngine(sheet, 40, {}, index::MatrixLayout::kFull);
  const std::vector<SurfacePoint> a = RandomPoints(sheet, 200, 3);
  for (size_t k = 0; k + 1 < a.size(); k += 2) {
    EXPECT_LT(flat->UnfoldingSpread(a[k], a[k + 1]), 1e-5 * flat->O1Distance(a[k], a[k + 1]));
  }
  const Mesh sphere = gen::Sphere(4, 1.0);
  auto round = MakeEngine(sphere, 100);
  const std::vector<SurfacePoint> b = RandomPoints(sphere, 400, 4);
  int spread = 0;
  for (size_t k = 0; k + 1 < b.size(); k += 2) {
    const double s = round->UnfoldingSpread(b[k], b[k + 1]);
    EXPECT_EQ(s, round->UnfoldingSpread(b[k + 1], b[k]));
    EXPECT_LT(s, 0.05 * round->O1Distance(b[k], b[k + 1]));
    if (round->Lift(b[k]).triangle == round->Lift(b[k + 1]).triangle) {
      EXPECT_EQ(s, 0);
    }
    spread += s > 1e-6;
  }
  EXPECT_GT(spread, 150);
}

// A closed tube is developable but not simply connected: geodesic triangles
// that straddle the cut locus of a far point (the line opposite it) unfold
// inconsistently, so pairs close to antipodal are not exact. The O(1)
// answer's error stays bounded and falls as samples are added (the default
// answer refines more of the coarse index's pairs, which are farther apart).
TEST(QueryEngineTest, ClosedCylinderErrorIsBoundedByTheCutLocus) {
  const Mesh m = gen::Cylinder(48, 16, 1.0, 3.0);
  auto coarse = MakeEngine(m, 40), fine = MakeEngine(m, 160);
  const DistanceOptions unfold{.near_pairs = NearPairs::kUnfold};
  const double e_coarse = MaxRelativeError(m, *coarse, 60, unfold),
               e_fine = MaxRelativeError(m, *fine, 60, unfold);
  // Measured 0.117 (m=40) and 0.061 (m=160): about twice that as the bound.
  EXPECT_LT(e_coarse, 0.25);
  EXPECT_LT(e_fine, 0.15);
  EXPECT_LT(e_fine, e_coarse);
}

TEST(QueryEngineTest, SphereRelativeErrorIsSmallAndFallsWithSamples) {
  const Mesh m = gen::Sphere(4, 1.0);
  const auto points = RandomPoints(m, 40, 5);
  double previous = 1;
  for (int32_t samples : {40, 160}) {
    auto engine = MakeEngine(m, samples);
    double sum2 = 0;
    int count = 0;
    for (size_t i = 0; i < 8; ++i) {
      geodesic::ExactGeodesicSolver solver(m);
      ASSERT_TRUE(solver.Propagate({points[i]}).ok());
      for (size_t j = 8; j < points.size(); ++j) {
        const double exact = solver.DistanceAt(points[j]);
        const double rel = (*engine->Distance(points[i], points[j]) - exact) / exact;
        sum2 += rel * rel;
        ++count;
      }
    }
    const double rms = std::sqrt(sum2 / count);
    EXPECT_LT(rms, previous);
    previous = rms;
  }
  EXPECT_LT(previous, 0.01);
}

TEST(QueryEngineTest, SymmetricZeroOnTheDiagonalAndInfiniteAcrossComponents) {
  const Mesh m = gen::Torus(48, 24, 2.0, 0.7);
  auto engine = MakeEngine(m, 60);
  const auto points = RandomPoints(m, 50, 3);
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(*engine->Distance(points[i], points[i]), 0.0);
    for (size_t j = 0; j < points.size(); j += 7) {
      EXPECT_EQ(*engine->Distance(points[i], points[j]), *engine->Distance(points[j], points[i]));
    }
  }
  // A point on an edge, described from either face, is the same point.
  const int32_t h = 5, g = m.Twin(h);
  const SurfacePoint on_h{Mesh::FaceOf(h), {0, 0, 0}};
  SurfacePoint a = on_h, b{Mesh::FaceOf(g), {0, 0, 0}};
  a.w[h % 3] = 0.3;
  a.w[(h + 1) % 3] = 0.7;
  b.w[g % 3] = 0.7;  // Origin(g) = Dest(h)
  b.w[(g + 1) % 3] = 0.3;
  EXPECT_EQ(*engine->Distance(a, b), 0.0);
  EXPECT_EQ(*engine->Distance(a, points[0]), *engine->Distance(b, points[0]));

  const Mesh two = gen::TwoComponents(10);
  auto split = MakeEngine(two, 20);
  int32_t far = 0;
  while (two.FaceComponent(far) == two.FaceComponent(0)) ++far;
  EXPECT_EQ(*split->Distance({0, {0.2, 0.3, 0.5}}, {far, {0.2, 0.3, 0.5}}),
            std::numeric_limits<double>::infinity());
  EXPECT_EQ(split->Path({0, {0.2, 0.3, 0.5}}, {far, {0.2, 0.3, 0.5}}).status().code(),
            absl::StatusCode::kNotFound);
}

TEST(QueryEngineTest, BatchEqualsSingleAndValidatesEveryPoint) {
  const Mesh m = gen::Sphere(3, 1.0);
  auto engine = MakeEngine(m, 40);
  // Far pairs (computed several at a time), pairs in one face (one at a
  // time), points at vertices, and lengths that are not a multiple of the
  // lanes: each answer is the single query's, to the bit.
  auto a = RandomPoints(m, 1003, 1), b = RandomPoints(m, 1003, 2);
  for (size_t i = 0; i < a.size(); i += 5) a[i].w = {0, 1, 0};
  for (size_t i = 0; i < a.size(); i += 7) b[i] = {a[i].face, {0.1, 0.2, 0.7}};
  for (size_t n : {size_t{1}, size_t{3}, size_t{5}, size_t{9}, a.size()}) {
    std::vector<double> out(n);
    ASSERT_TRUE(engine->DistanceBatch(std::span(a).first(n), std::span(b).first(n), out).ok());
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(out[i], *engine->Distance(a[i], b[i])) << i;
  }
  const Mesh two = gen::TwoComponents(10);
  auto split = MakeEngine(two, 20);
  const auto c = RandomPoints(two, 64, 3), d = RandomPoints(two, 64, 4);
  std::vector<double> split_out(c.size());
  ASSERT_TRUE(split->DistanceBatch(c, d, split_out).ok());
  int infinite = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    EXPECT_EQ(split_out[i], *split->Distance(c[i], d[i]));
    infinite += std::isinf(split_out[i]);
  }
  EXPECT_GT(infinite, 0);
  EXPECT_LT(infinite, static_cast<int>(c.size()));

  // Points are checked where they enter (input_queries_test.cc); the
  // engine checks the batch's shape.
  std::vector<double> out(a.size() - 1);
  EXPECT_EQ(engine->DistanceBatch(a, b, out).code(), absl::StatusCode::kInvalidArgument);
}

TEST(QueryEngineTest, ExactNearPairsMatchTheExactEngine) {
  const Mesh m = gen::Sphere(4, 1.0);
  auto engine = MakeEngine(m, 60);
  const DistanceOptions options{.near_pairs = NearPairs::kExact};
  QueryScratch scratch;
  const auto points = RandomPoints(m, 400, 9);
  int near = 0;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    if (!engine->IsNearPair(points[i], points[i + 1])) continue;
    ++near;
    const double exact = Exact(m, points[i], points[i + 1]);
    EXPECT_NEAR(*engine->Distance(points[i], points[i + 1], options, &scratch), exact,
                1e-9 * (1 + exact));
    // Without a scratch, the same answer.
    EXPECT_NEAR(*engine->Distance(points[i], points[i + 1], options), exact, 1e-9 * (1 + exact));
  }
  EXPECT_GT(near, 0);
}

TEST(QueryEngineTest, NearPairsAreThePathLengthByDefault) {
  const Mesh m = gen::Grid(30, 30, 1.0, 1.0, 0.2, 4);
  auto engine = MakeEngine(m, 40);
  const DistanceOptions unfold{.near_pairs = NearPairs::kUnfold};
  const auto points = RandomPoints(m, 800, 12);
  int near = 0;
  double worst = 0, worst_unfold = 0;
  std::vector<SurfacePoint> a, b;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    const SurfacePoint& p = points[i];
    const SurfacePoint& q = points[i + 1];
    if (!engine->IsNearPair(p, q)) continue;
    ++near;
    a.push_back(p);
    b.push_back(q);
    const double d = *engine->Distance(p, q);
    EXPECT_EQ(d, *engine->Distance(q, p));
    // A path's length: Path's own, or longer when Path's restarts found a
    // shorter one.
    auto path = engine->Path(p, q);
    ASSERT_TRUE(path.ok());
    EXPECT_GE(d, PathLength(*path) * (1 - 1e-12));
    const double exact = Exact(m, p, q);
    EXPECT_GE(d, exact * (1 - 1e-9));  // a surface path
    worst = std::max(worst, (d - exact) / exact);
    worst_unfold =
        std::max(worst_unfold, std::abs(*engine->Distance(p, q, unfold) - exact) / exact);
  }
  EXPECT_GT(near, 10);
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(worst, worst_unfold);
  std::vector<double> out(a.size());
  ASSERT_TRUE(engine->DistanceBatch(a, b, out).ok());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(out[i], *engine->Distance(a[i], b[i]));
}

// Near pairs the chord's walks vouch for no local geodesic between are
// answered exactly (a propagation confined round the pair), with a bound of
// rounding size: here pairs across a hole, where the chord leaves the
// surface and the geodesic bends round the hole's corner.
TEST(QueryEngineTest, NearPairsTheWalksCannotSettleAreExact) {
  const Mesh m = gen::SquareWithHole(24, 1.0);
  auto engine = geodex::testing::TestEngineOrThrow(m, 20, /*calibrate=*/true);
  QueryScratch scratch;
  std::vector<SurfacePoint> left, right;
  for (const SurfacePoint& p : RandomPoints(m, 3000, 33)) {
    const mesh::Vec3 x = mesh::PositionOf(m, p);
    if (std::abs(x.y() - 0.5) > 0.12) continue;
    if (x.x() < 0.3) left.push_back(p);
    if (x.x() > 0.7) right.push_back(p);
  }
  int near = 0, unsettled = 0;
  for (size_t i = 0; i < std::min(left.size(), right.size()); ++i) {
    const SurfacePoint& p = left[i];
    const SurfacePoint& q = right[i];
    const double o1 = *engine->Distance(p, q, {.near_pairs = NearPairs::kUnfold});
    if (!engine->IsNearPair(p, q) && o1 >= engine->refine_below()) continue;
    ++near;
    double bound = 0;
    const double d = *engine->Distance(p, q, {}, &scratch, &bound);
    const double exact = Exact(m, p, q);
    if (engine->WalkedDistance(p, q).ok()) {
      EXPECT_GE(d, exact * (1 - 1e-9));  // a surface path
      continue;
    }
    ++unsettled;
    EXPECT_NEAR(d, exact, 1e-9 * exact);
    EXPECT_LE(bound, kExactRelativeBound * d);
    EXPECT_GE(bound, std::abs(d - exact));
    // Symmetric, and the same in a batch.
    EXPECT_EQ(*engine->Distance(q, p, {}, &scratch), d);
    double out = 0;
    ASSERT_TRUE(engine->DistanceBatch({&p, 1}, {&q, 1}, {&out, 1}).ok());
    EXPECT_EQ(out, d);
  }
  EXPECT_GT(near, 10);
  EXPECT_GT(unsettled, 10);
}

// A request that raises the threshold past every pair (the every-distance
// mode at its extreme) refines them all: within the index's own threshold
// each answer is the walks' local geodesic or exact; beyond it a surface
// path (a walk or the gradient trace) no longer than the O(1) answer plus
// its bound (this index has none), or the O(1) answer where none is found;
// much better than the O(1) answer on a coarse index. A threshold it cannot
// parse is refused. (The bounds of these answers: tests/bench/accuracy.md.)
TEST(QueryEngineTest, ARequestRaisesTheRefinementThresholdInL1000) {
  const Mesh m = gen::Torus(48, 24, 1.0, 0.45);
  auto engine = MakeEngine(m, 60);
  EXPECT_NEAR(engine->l1000(), engine->scale_length() * std::sqrt(60 / 1000.0), 1e-12);
  const DistanceOptions every{.refine_below_l1000 = 1e6};
  const auto points = RandomPoints(m, 120, 5);
  double o1_worst = 0, every_worst = 0;
  geodesic::ExactGeodesicSolver solver(m);
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    const SurfacePoint& p = points[i];
    const SurfacePoint& q = points[i + 1];
    ASSERT_TRUE(solver.Propagate({p}).ok());
    const double exact = solver.DistanceAt(q);
    const double o1 = *engine->Distance(p, q, {.near_pairs = NearPairs::kUnfold});
    const double refined = *engine->Distance(p, q, every);
    const auto walked = engine->WalkedDistance(p, q);
    const double exactly =
        *engine->Distance(p, q, {.near_pairs = NearPairs::kExact, .refine_below_l1000 = 1e6});
    const bool own_band = *engine->Distance(p, q) != o1;  // refined by default too
    if (own_band) {
      EXPECT_TRUE((walked.ok() && std::abs(refined - *walked) <= 1e-12 * refined) ||
                  refined == exactly)
          << refined << " walked " << (walked.ok() ? *walked : -1) << " exact " << exactly;
    } else {
      EXPECT_TRUE(refined >= exact * (1 - 1e-9) || refined == o1) << refined << " " << exact;
    }
    EXPECT_NEAR(exactly, exact, 1e-9 * exact);
    double out = 0;
    ASSERT_TRUE(engine->DistanceBatch({&p, 1}, {&q, 1}, {&out, 1}, every).ok());
    EXPECT_EQ(out, refined);
    o1_worst = std::max(o1_worst, std::abs(o1 - exact) / exact);
    every_worst = std::max(every_worst, std::abs(refined - exact) / exact);
  }
  EXPECT_GT(o1_worst, 0.03);  // 60 samples: the O(1) answer errs by several %
  EXPECT_LT(every_worst, o1_worst / 3);
  for (const double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const absl::StatusOr<double> d =
        engine->Distance(points[0], points[1], {.refine_below_l1000 = bad});
    EXPECT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument) << bad;
  }
}

// A refined answer's bound says what refined it: an exact answer carries
// the rounding bound (kExactRelativeBound) alone; in the index's own band a
// walk carries the smaller of its calibrated bound and its certificate, no
// more than the O(1) answer's; every bound covers its answer's error,
// beyond the index's own threshold too, where the O(1) answer's floor is
// set aside when the walk is shorter than it.
TEST(QueryEngineTest, ARefinedAnswersBoundSaysWhatRefinedIt) {
  const Mesh m = gen::Torus(48, 24, 1.0, 0.45);
  auto engine = geodex::testing::TestEngineOrThrow(m, 60, /*calibrate=*/true);
  ASSERT_TRUE(engine->has_error_bounds());
  const auto points = RandomPoints(m, 300, 23);
  geodesic::ExactGeodesicSolver solver(m);
  QueryScratch scratch;
  int refined = 0, raised = 0;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    const SurfacePoint& p = points[i];
    const SurfacePoint& q = points[i + 1];
    ASSERT_TRUE(solver.Propagate({p}).ok());
    const double exact = solver.DistanceAt(q);
    const double slack = 1e-9 * exact;
    double o1_bound = 0, bound = 0, every_bound = 0, exact_bound = 0;
    const double o1 =
        *engine->Distance(p, q, {.near_pairs = NearPairs::kUnfold}, &scratch, &o1_bound);
    const double d = *engine->Distance(p, q, {}, &scratch, &bound);
    if (d != o1) {
      ++refined;
      EXPECT_LE(bound, o1_bound) << "pair " << i / 2 << ": " << d << " against O(1) " << o1;
      EXPECT_LE(std::abs(d - exact), bound + slack) << "pair " << i / 2;
    }
    const double every =
        *engine->Distance(p, q, {.refine_below_l1000 = 1e6}, &scratch, &every_bound);
    if (every != o1 && d == o1) {
      ++raised;
      EXPECT_LE(std::abs(every - exact), every_bound + slack)
          << "pair " << i / 2 << ": " << every << " exact " << exact << " O(1) " << o1;
    }
    const double exactly = *engine->Distance(
        p, q, {.near_pairs = NearPairs::kExact, .refine_below_l1000 = 1e6}, &scratch, &exact_bound);
    EXPECT_NEAR(exactly, exact, slack);
    EXPECT_EQ(exact_bound, kExactRelativeBound * exactly);
  }
  EXPECT_GT(refined, 5);
  EXPECT_GT(raised, 25);
}

// An O(1) answer that overestimates puts a pair closer than 3L above 3L; a
// calibrated index also refines the pairs its bound says may be closer, and
// every index the pairs whose chord is below its threshold while the answer
// overestimates by less than kChordNet (refinement.h).
TEST(QueryEngineTest, PairsThatMayBeCloserThan3LAreRefined) {
  const Mesh m = gen::Torus(48, 24, 1.0, 0.45);
  auto plain = MakeEngine(m, 150);
  auto calibrated = geodex::testing::TestEngineOrThrow(m, 150, /*calibrate=*/true);
  const double three_l = kRefineScale * plain->scale_length();
  EXPECT_EQ(plain->refine_below(), three_l);
  EXPECT_GT(calibrated->refine_below(), three_l);
  EXPECT_LT(calibrated->refine_below(), 2 * three_l);
  const DistanceOptions unfold{.near_pairs = NearPairs::kUnfold};
  const auto points = RandomPoints(m, 3000, 21);
  int in_margin = 0, in_net = 0;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    const SurfacePoint& p = points[i];
    const SurfacePoint& q = points[i + 1];
    if (plain->IsNearPair(p, q)) continue;
    const double o1 = *plain->Distance(p, q, unfold);
    ASSERT_EQ(o1, *calibrated->Distance(p, q, unfold));  // the same index otherwise
    const double chord = (PositionOf(m, p) - PositionOf(m, q)).norm();
    for (const QueryEngine* engine : {plain.get(), calibrated.get()}) {
      const double below = engine->refine_below();
      const bool margin = o1 >= three_l && o1 < below;
      const bool net = o1 >= below && o1 < kChordNet * below && chord < below;
      if (!margin && !net) {
        if (o1 >= three_l) {
          EXPECT_EQ(*engine->Distance(p, q), o1);
        }
        continue;
      }
      (margin ? in_margin : in_net) += 1;
      // Refined: the walks' local geodesic, a doubted walk its lower bound
      // certifies (a surface path within 2% of the geodesic), or the exact
      // distance where the walks vouch for none (or ran longer than is
      // plausible).
      const auto walked = engine->WalkedDistance(p, q);
      const double exact = *engine->Distance(p, q, {.near_pairs = NearPairs::kExact});
      const double refined = *engine->Distance(p, q);
      // Two straight walks in different corridors agree to rounding.
      const bool certified = refined >= exact * (1 - 1e-12) && refined <= 1.02 * exact;
      EXPECT_TRUE((walked.ok() && std::abs(refined - *walked) <= 1e-12 * refined) ||
                  refined == exact || certified)
          << refined << " walked " << (walked.ok() ? *walked : -1) << " exact " << exact;
    }
  }
  EXPECT_GT(in_margin, 5);
  EXPECT_GT(in_net, 5);
}

TEST(QueryEngineTest, PathsStayOnTheSurfaceAndAreNearlyGeodesic) {
  const Mesh m = gen::Grid(30, 30, 1.0, 1.0, 0.2, 4);
  auto engine = MakeEngine(m, 40);
  const auto points = RandomPoints(m, 40, 8);
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    auto path = engine->Path(points[i], points[i + 1]);
    ASSERT_TRUE(path.ok()) << path.status();
    ASSERT_GE(path->size(), 2u);
    const mesh::Vec3 a = PositionOf(m, points[i]), b = PositionOf(m, points[i + 1]);
    EXPECT_EQ(path->front().position, a);
    EXPECT_EQ(path->back().position, b);
    double length = 0;
    for (size_t k = 1; k < path->size(); ++k) {
      length += ((*path)[k].position - (*path)[k - 1].position).norm();
      EXPECT_LT(std::abs((*path)[k].position.z()), 1e-12);  // on the plane
    }
    EXPECT_LE(length, (a - b).norm() * 1.01 + 1e-9);
  }
}

// Consecutive points share a face of the mesh.
bool SharesFaces(const Mesh& m, const std::vector<PathPoint>& path) {
  auto support = [&](const PathPoint& p) {
    std::vector<int32_t> out;
    for (int i = 0; i < 3; ++i) {
      if (p.point.w[i] > 1e-12) out.push_back(m.face(p.point.face)[i]);
    }
    return out;
  };
  for (size_t k = 1; k < path.size(); ++k) {
    std::vector<int32_t> both = support(path[k - 1]);
    for (int32_t v : support(path[k])) both.push_back(v);
    bool shared = false;
    for (int32_t f = 0; f < m.num_faces() && !shared; ++f) {
      shared = std::all_of(both.begin(), both.end(), [&](int32_t v) {
        const auto t = m.face(f);
        return t[0] == v || t[1] == v || t[2] == v;
      });
    }
    if (!shared) return false;
  }
  return true;
}

// Straightened through the faces it crosses, a traced path on a developable
// surface is the exact geodesic, and never longer than the trace.
TEST(QueryEngineTest, StraightenedPathsAreExactOnDevelopableSurfaces) {
  for (const Mesh& m :
       {gen::Grid(30, 30, 1.0, 1.0, 0.2, 4), gen::FoldedSheet(30, 20, 2.0, 1.0, 1.1)}) {
    auto engine = MakeEngine(m, 40);
    const auto points = RandomPoints(m, 40, 8);
    for (size_t i = 0; i + 1 < points.size(); i += 2) {
      auto path = engine->Path(points[i], points[i + 1]);
      auto traced = engine->TracePath(points[i], points[i + 1]);
      ASSERT_TRUE(path.ok() && traced.ok());
      EXPECT_EQ(path->front().position, PositionOf(m, points[i]));
      EXPECT_EQ(path->back().position, PositionOf(m, points[i + 1]));
      EXPECT_TRUE(SharesFaces(m, *path)) << m.name() << " pair " << i;
      const double exact = Exact(m, points[i], points[i + 1]);
      EXPECT_NEAR(PathLength(*path), exact, 1e-9 * (1 + exact)) << m.name() << " pair " << i;
      EXPECT_LE(PathLength(*path), PathLength(*traced) + 1e-12);
    }
  }
}

// The pairs the default mode refines get the length of a straight path
// through the faces between them (the walk of the chord, or the trace), exact
// to double precision on developable surfaces: across a sharp fold, round a
// half cylinder, and from vertices (the O(1) answer is exact only to float
// precision there, so it would not pass).
TEST(QueryEngineTest, RefinedNearPairsAreExactOnDevelopableSurfaces) {
  for (const Mesh& m : {gen::FoldedSheet(24, 16, 2.0, 1.0, 2.5), HalfCylinder(24, 16, 1.0, 3.0)}) {
    SCOPED_TRACE(m.name());
    auto engine = MakeEngine(m, 60);
    const DistanceOptions unfold{.near_pairs = NearPairs::kUnfold};
    auto points = RandomPoints(m, 1200, 5);
    // Pairs of vertices, a vertex and an interior point, interior points.
    for (size_t i = 0; i + 1 < points.size(); i += 2) {
      if ((i / 2) % 3 < 2) points[i].w = {1, 0, 0};
      if ((i / 2) % 3 < 1) points[i + 1].w = {0, 1, 0};
    }
    int refined = 0;
    for (size_t i = 0; i + 1 < points.size(); i += 2) {
      const SurfacePoint& p = points[i];
      const SurfacePoint& q = points[i + 1];
      if (*engine->Distance(p, q, unfold) >= engine->refine_below()) continue;
      ++refined;
      const double exact = Exact(m, p, q);
      EXPECT_NEAR(*engine->Distance(p, q), exact, 1e-9 * (1 + exact)) << "pair " << i;
      EXPECT_EQ(*engine->Distance(p, q), *engine->Distance(q, p));
    }
    EXPECT_GT(refined, 20);
  }
}

// The approximate field of a coarse index has local minima and flats; path
// tracing must still always arrive, on the surface.
TEST(QueryEngineTest, ExactCorridorPathsAreExactWhereTheTraceIsNot) {
  const Mesh m = gen::Torus(48, 24, 2.0, 0.7);
  auto traced = MakeEngine(m, 60);
  QueryOptions options;
  options.exact_path_corridor = 6;
  auto corridor = MakeEngine(m, 60, options);
  const auto points = RandomPoints(m, 80, 14);
  double worst_traced = 0, worst_corridor = 0;
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    auto plain = traced->Path(points[i], points[i + 1]);
    auto path = corridor->Path(points[i], points[i + 1]);
    ASSERT_TRUE(plain.ok() && path.ok());
    // The ends are the traced path's (Path gives them exactly as given).
    EXPECT_EQ(path->front().position, plain->front().position);
    EXPECT_EQ(path->back().position, plain->back().position);
    EXPECT_LT((path->back().position - PositionOf(m, points[i + 1])).norm(), 1e-12);
    EXPECT_TRUE(SharesFaces(m, *path)) << "pair " << i;
    const double exact = Exact(m, points[i], points[i + 1]);
    EXPECT_GE(PathLength(*path), exact * (1 - 1e-9));
    EXPECT_LE(PathLength(*path), PathLength(*plain) * (1 + 1e-12));
    worst_traced = std::max(worst_traced, PathLength(*plain) / exact);
    worst_corridor = std::max(worst_corridor, PathLength(*path) / exact);
  }
  std::printf("path / exact, worst: traced %.5f, with the exact corridor %.5f\n", worst_traced,
              worst_corridor);
  EXPECT_GT(worst_traced, 1.001);
  EXPECT_LT(worst_corridor, 1 + 1e-6);
}

TEST(QueryEngineTest, PathsAlwaysArriveOnACoarseCube) {
  const Mesh m = gen::Cube(12, 2.0);
  auto engine = MakeEngine(m, 40);
  const auto points = RandomPoints(m, 60, 21);
  for (size_t i = 0; i + 1 < points.size(); i += 2) {
    auto path = engine->Path(points[i], points[i + 1]);
    ASSERT_TRUE(path.ok()) << path.status();
    EXPECT_EQ(path->front().position, PositionOf(m, points[i]));
    EXPECT_EQ(path->back().position, PositionOf(m, points[i + 1]));
    for (const PathPoint& p : *path) {
      const mesh::Vec3 x = p.position;
      // On the cube's surface: some coordinate at 0 or 2, all within [0, 2].
      const double to_face = std::min({x.x(), x.y(), x.z(), 2 - x.x(), 2 - x.y(), 2 - x.z()});
      EXPECT_NEAR(to_face, 0, 1e-9);
    }
  }
}

TEST(QueryEngineTest, FieldIsTheMinimumOverSources) {
  const Mesh m = gen::Sphere(3, 1.0);
  auto engine = MakeEngine(m, 40);
  const auto sources = RandomPoints(m, 3, 6);
  auto field = engine->Field(sources);
  ASSERT_TRUE(field.ok());
  for (int32_t v = 0; v < m.num_vertices(); v += 13) {
    const SurfacePoint p = *mesh::VertexPoint(m, v);
    double best = 1e300;
    int32_t nearest = -1;
    for (int32_t s = 0; s < 3; ++s) {
      const double d = engine->O1Distance(sources[s], p);
      if (d < best) best = d, nearest = s;
    }
    EXPECT_NEAR(field->distance[v], best, 1e-12);
    EXPECT_EQ(field->nearest[v], nearest);
  }
  EXPECT_EQ(engine->Field({}).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(QueryEngineTest, LocateFindsSurfacePoints) {
  const Mesh m = gen::Sphere(3, 1.0);
  auto engine = MakeEngine(m, 30);
  for (const SurfacePoint& p : RandomPoints(m, 50, 2)) {
    const mesh::Vec3 x = PositionOf(m, p);
    auto located = engine->Locate(x * 1.0);
    ASSERT_TRUE(located.ok());
    EXPECT_LT((PositionOf(m, located->point) - x).norm(), 1e-12);
  }
}

TEST(QueryEngineTest, LinearBaselineIsWorseThanUnfolding) {
  const Mesh m = gen::Sphere(4, 1.0);
  auto engine = MakeEngine(m, 60);
  const auto points = RandomPoints(m, 30, 4);
  double unfold2 = 0, linear2 = 0;
  for (size_t i = 0; i < 5; ++i) {
    geodesic::ExactGeodesicSolver solver(m);
    ASSERT_TRUE(solver.Propagate({points[i]}).ok());
    for (size_t j = 5; j < points.size(); ++j) {
      const double exact = solver.DistanceAt(points[j]);
      unfold2 += std::pow((*engine->Distance(points[i], points[j]) - exact) / exact, 2);
      linear2 +=
          std::pow((engine->LinearInterpolationDistance(points[i], points[j]) - exact) / exact, 2);
    }
  }
  EXPECT_LT(unfold2, linear2);
}

}  // namespace
}  // namespace geodex::query
