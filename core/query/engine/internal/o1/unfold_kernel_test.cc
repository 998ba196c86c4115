#include "core/query/engine/internal/o1/unfold_kernel.h"

#include <cstring>
#include <random>
#include <vector>

#include "gtest/gtest.h"

namespace geodex::query::kernel {
namespace {

// The three edge frames of a planar triangle with the given side lengths
// (as QueryEngine derives them from sample distances), or of a degenerate
// one when a side is 0.
void Frames(double ab, double bc, double ca, Frame<double>* out) {
  const double side[3] = {ab, bc, ca};
  for (int i = 0; i < 3; ++i) {
    const double l = side[i], to_a = side[(i + 2) % 3], to_b = side[(i + 1) % 3];
    Frame<double>& e = out[i];
    e.l = l;
    if (l > 0) {
      geometry::Place(l, to_a, to_b, &e.cx, &e.cy);
      e.inv_2l = 1 / (2 * l);
    } else {
      e.cx = e.cy = e.inv_2l = 0;
    }
  }
}

// Random far pairs, including the awkward ones: degenerate edges, shared
// corners, distances that break the triangle inequality, points on an
// edge's line, float32-rounded values.
struct RandomPairs {
  std::vector<Frame<double>> frames;
  std::vector<double> distances;
  std::vector<FarPair> pairs;

  explicit RandomPairs(int n, uint32_t seed) : frames(6 * n), distances(6 * n), pairs(n) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    auto value = [&](double scale) {
      const double r = u(rng);
      if (r < 0.03) return 0.0;
      double v = scale * (0.05 + 2 * u(rng));
      if (r < 0.3) v = static_cast<float>(v);
      return v;
    };
    for (int k = 0; k < n; ++k) {
      for (int t = 0; t < 2; ++t) {
        const double ab = value(1), bc = value(1);
        // Often a valid triangle, sometimes not, sometimes flat.
        double ca = u(rng) < 0.8 ? ab + bc * (u(rng) * 1.6 - 0.8) : value(1);
        if (u(rng) < 0.05) ca = ab + bc;
        Frames(ab, bc, std::abs(ca), &frames[6 * k + 3 * t]);
      }
      for (int i = 0; i < 6; ++i) distances[6 * k + i] = value(1);
      FarPair& pair = pairs[k];
      pair.p_frames = &frames[6 * k];
      pair.q_frames = &frames[6 * k + 3];
      pair.p_distance = &distances[6 * k];
      pair.q_distance = &distances[6 * k + 3];
      for (int j = 0; j < 3; ++j) {
        for (int i = 0; i < 3; ++i) pair.e[j][i] = value(4);
        pair.shared[j] = u(rng) < 0.1 ? pair.p_distance[j] : -1;
      }
    }
  }
};

TEST(UnfoldKernelTest, Avx2LanesEqualOnePairAtATimeToTheBit) {
  if (!HasAvx2Lanes()) GTEST_SKIP() << "this build or CPU has no AVX2: the lanes are not used";
  const RandomPairs random(40000, 5);
  for (size_t k = 0; k + kLanes <= random.pairs.size(); k += kLanes) {
    double lanes[kLanes], one[kLanes];
    FarDistancesAvx2(&random.pairs[k], lanes);
    FarDistancesOneByOne(&random.pairs[k], one);
    for (int i = 0; i < kLanes; ++i) {
      ASSERT_EQ(std::memcmp(&lanes[i], &one[i], sizeof(double)), 0)
          << "pair " << k + i << ": " << lanes[i] << " vs " << one[i];
    }
  }
}

// The unfolding of core/geometry/planar_unfolding.h as the kernel instantiates it
// (PlaceOn: AlongEdgeInv2l and HeightSquared; HeightFromThirdCorner), in
// lanes and one point at a time.
TEST(UnfoldKernelTest, Avx2PlacementEqualsOnePointAtATimeToTheBit) {
  if (!HasAvx2Lanes()) GTEST_SKIP() << "this build or CPU has no AVX2: the lanes are not used";
  const RandomPairs random(40000, 7);
  for (size_t k = 0; k + kLanes <= random.pairs.size(); k += kLanes) {
    const Frame<double>* frames[kLanes];
    const double* d[kLanes];
    for (int i = 0; i < kLanes; ++i) {
      frames[i] = random.pairs[k + i].p_frames;
      d[i] = random.pairs[k + i].p_distance;
    }
    Placed<double> lanes[kLanes];
    PlaceInTriangleAvx2(frames, d, lanes);
    for (int i = 0; i < kLanes; ++i) {
      const Placed<double> one = PlaceInTriangle(frames[i], d[i]);
      ASSERT_EQ(std::memcmp(&lanes[i], &one, sizeof(one)), 0) << "point " << k + i;
    }
  }
}

TEST(UnfoldKernelTest, DevelopableCaseIsExact) {
  // Two triangles of one plane: p in the first, q in the second, far apart;
  // the unfolded distance is the planar one.
  const double a[2] = {0, 0}, b[2] = {1, 0}, c[2] = {0.3, 0.9};    // p's triangle
  const double d[2] = {5, 1}, e[2] = {6, 0.5}, f[2] = {5.6, 1.8};  // q's triangle
  const double p[2] = {0.4, 0.3}, q[2] = {5.5, 1.1};
  auto dist = [](const double* x, const double* y) { return std::hypot(x[0] - y[0], x[1] - y[1]); };
  Frame<double> pf[3], qf[3];
  Frames(dist(a, b), dist(b, c), dist(c, a), pf);
  Frames(dist(d, e), dist(e, f), dist(f, d), qf);
  const double pd[3] = {dist(p, a), dist(p, b), dist(p, c)};
  const double qd[3] = {dist(q, d), dist(q, e), dist(q, f)};
  FarPair pair{pf, qf, pd, qd, {}, {-1, -1, -1}};
  const double* q_corner[3] = {d, e, f};
  const double* p_corner[3] = {a, b, c};
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) pair.e[j][i] = dist(q_corner[j], p_corner[i]);
  }
  EXPECT_NEAR(FarDistance(pair), dist(p, q), 1e-12);
  FarPair four[kLanes] = {pair, pair, pair, pair};
  double out[kLanes];
  FarDistances(four, out);
  for (double x : out) EXPECT_EQ(x, FarDistance(pair));
}

}  // namespace
}  // namespace geodex::query::kernel
