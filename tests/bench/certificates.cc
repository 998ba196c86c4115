// certificates: which lower bound on a pair's geodesic distance certifies
// the walk a near pair's refinement found, so that the walk is taken without
// an exact solve. A walk is certified when it is no longer than 1.02 times
// the bound: it then errs less than 2%, whichever corridor it took.
//
//   certificates --index X.gdx... [--pairs 400]
//
// Two sets of interior pairs per index: near pairs (the O(1) answer at L-3L
// of the index's own L; a random point and one a random walk of faces away)
// and area-uniform pairs whose O(1) answer is 1-8 L1000. For each pair: the
// exact distance (the engine's exact mode), the walk (shots, then the
// chord's walks: chord_walk.h) and these bounds:
//   chord      |pq|, never longer than the geodesic;
//   O(1)+bound the refinement's acceptance in the raised band: the walk is
//              no longer than the O(1) answer plus its calibrated bound (not
//              a lower bound: the share of such walks more than 2% off the
//              exact distance is printed);
//   landmarks  |d(p,s) - d(q,s)| <= d(p,q) for any sample s (the ALT bound
//              of road routing): k = 3, the corners of p's geodesic
//              triangle, or the k/2 samples nearest each end, k = 8 and 16,
//              with exact d(p,s) and d(q,s) at the points (what storing each
//              face's unfolded landmark sources would give: its upper
//              limit); and k = 3 as the index stores it today, exact at
//              vertices only, a face's point bounded by its corners'
//              distances less or plus its distance to them;
//   cut        two chords through the border of the faces nearer p than q
//              (cut_bound.h), reaching kCutReach x the walk round the
//              points, as the refinement computes it.
// Per bound: the median slack (d - bound) / d, the share of pairs certified,
// the µs a pair it costs where it is computed at query time and the bytes a
// bound needs per face beyond today's index.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/strings/str_format.h"
#include "core/index/index.h"
#include "core/query/engine/internal/bounds/refinement.h"
#include "core/query/engine/internal/exact/local_exact.h"
#include "core/query/engine/internal/o1/lifted_unfolding.h"
#include "core/query/engine/internal/o1/lifting.h"
#include "core/query/engine/internal/paths/chord_walk.h"
#include "core/query/engine/internal/paths/cut_bound.h"
#include "core/query/engine/internal/paths/gradient_path.h"
#include "core/query/engine/query_engine.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/query_bench_lib.h"

namespace geodex::bench {
namespace {

using mesh::SurfacePoint;
using Points = std::vector<SurfacePoint>;

constexpr double kCertified = 1.02;
constexpr int kBounds = 7;
constexpr int kCut = 6;
constexpr const char* kBoundNames[kBounds] = {"chord",
                                              "O(1)+bound (acceptance)",
                                              "landmarks k=3, exact at points",
                                              "landmarks k=8, exact at points",
                                              "landmarks k=16, exact at points",
                                              "landmarks k=3 as stored (vertices)",
                                              "cut: two chords through the border"};

// The parts a walk needs, over the index (as the engine holds them).
struct Parts {
  explicit Parts(const index::Index& ix)
      : view{ix.positions(), ix.faces(), ix.twins()},
        unfolding(ix, true),
        lifting(view, ix.vertices(), unfolding),
        paths(view, lifting, unfolding, true),
        exact(ix, view) {}
  query::MeshView view;
  query::LiftedUnfolding unfolding;
  query::Lifting lifting;
  query::GradientPaths paths;
  query::LocalExact exact;
};

struct Tally {
  std::vector<double> slack[kBounds];
  int certified[kBounds] = {};
  int accepted_wrong = 0;  // O(1)+bound acceptances more than 2% off
  int pairs = 0, walked = 0;
  double cut_seconds = 0;
};

// The k samples nearest a point by exact distance (`d`: exact distances from
// the point to every vertex, +inf beyond the propagation's radius).
std::vector<int32_t> Nearest(const index::Index& ix, std::span<const double> d, size_t k) {
  std::vector<int32_t> order(ix.num_samples());
  for (int32_t s = 0; s < ix.num_samples(); ++s) order[s] = s;
  k = std::min(k, order.size());
  std::partial_sort(order.begin(), order.begin() + k, order.end(),
                    [&](int32_t a, int32_t b) { return d[ix.samples()[a]] < d[ix.samples()[b]]; });
  order.resize(k);
  return order;
}

// max over landmarks s of |d(p,s) - d(q,s)|, from exact vertex distances of
// p (dp) and q (dq).
double LandmarkBound(const index::Index& ix, std::span<const int32_t> landmarks,
                     std::span<const double> dp, std::span<const double> dq) {
  double best = 0;
  for (const int32_t s : landmarks) {
    const int32_t v = ix.samples()[s];
    if (std::isfinite(dp[v]) && std::isfinite(dq[v]))
      best = std::max(best, std::abs(dp[v] - dq[v]));
  }
  return best;
}

// The stored k = 3 bound: the corners of the triangles of p's and q's
// vertices, each point's distance to a corner bounded through the vertices
// of its face that store it.
double StoredBound(const index::Index& ix, const query::MeshView& view, const SurfacePoint& p,
                   const SurfacePoint& q) {
  auto range = [&](const SurfacePoint& x, int32_t s, double* low, double* high) {
    *low = -1e300;
    *high = 1e300;
    const mesh::Vec3 at = view.PositionOf(x);
    for (int i = 0; i < 3; ++i) {
      const int32_t v = view.Vertex(x.face, i);
      const index::VertexRecord& r = ix.vertices()[v];
      if (r.triangle < 0) continue;
      for (int c = 0; c < 3; ++c) {
        if (ix.triangles()[r.triangle].corner[c] != s) continue;
        const double e = (view.Position(v) - at).norm();
        *low = std::max(*low, r.distance[c] - e);
        *high = std::min(*high, r.distance[c] + e);
      }
    }
    return *low > -1e300;
  };
  double best = 0;
  for (const SurfacePoint* x : {&p, &q}) {
    for (int i = 0; i < 3; ++i) {
      const index::VertexRecord& r = ix.vertices()[view.Vertex(x->face, i)];
      if (r.triangle < 0) continue;
      for (const int32_t s : ix.triangles()[r.triangle].corner) {
        double pl, ph, ql, qh;
        if (range(p, s, &pl, &ph) && range(q, s, &ql, &qh)) {
          best = std::max({best, ql - ph, pl - qh});
        }
      }
    }
  }
  return best;
}

void Measure(const index::Index& ix, const query::QueryEngine& engine, Parts& parts, bool near,
             const SurfacePoint& p, const SurfacePoint& q, query::QueryScratch& scratch,
             Tally* tally) {
  const absl::StatusOr<double> exact =
      engine.Distance(p, q, {.near_pairs = query::NearPairs::kExact}, &scratch);
  double bound = 0;
  const absl::StatusOr<double> o1 =
      engine.Distance(p, q, {.near_pairs = query::NearPairs::kUnfold}, &scratch, &bound);
  if (!exact.ok() || !o1.ok() || !(*exact > 0)) return;
  const double d = *exact, reach = d + 3 * engine.scale_length();
  std::vector<double> dp, dq;
  if (auto s = parts.exact.Distances(p, reach, scratch); s.ok()) dp.assign(s->begin(), s->end());
  if (auto s = parts.exact.Distances(q, reach, scratch); s.ok()) dq.assign(s->begin(), s->end());
  if (dp.empty() || dq.empty()) return;
  ++tally->pairs;
  // Walked as the refinement walks: under the O(1) answer plus its bound,
  // shots held within kShotExcess of the O(1) answer beyond the near band.
  const query::NearWalk walk =
      query::WalkNearPair(parts.view, p, q,
                          {.plausible = *o1 + bound,
                           .plausible_shot = near ? query::kInf : (1 + query::kShotExcess) * *o1,
                           .heading = parts.paths.Heading(p, q),
                           .shoot = !near},
                          &scratch);
  const double chord = (parts.view.PositionOf(p) - parts.view.PositionOf(q)).norm();
  std::vector<int32_t> k3;
  {
    const int heaviest = static_cast<int>(std::max_element(p.w.begin(), p.w.end()) - p.w.begin());
    const index::VertexRecord& r = ix.vertices()[parts.view.Vertex(p.face, heaviest)];
    if (r.triangle >= 0)
      k3.assign(ix.triangles()[r.triangle].corner, ix.triangles()[r.triangle].corner + 3);
  }
  auto near_both = [&](size_t k) {
    std::vector<int32_t> a = Nearest(ix, dp, k / 2), b = Nearest(ix, dq, k / 2);
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  const double w = walk.path ? walk.path->length : NAN;
  const auto start = std::chrono::steady_clock::now();
  const double cut = query::CutLowerBound(parts.view, p, q, query::kCutReach * (walk.path ? w : d),
                                          query::kCutFaces, &scratch.walks());
  tally->cut_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double lower[kBounds] = {chord,
                                 NAN,
                                 LandmarkBound(ix, k3, dp, dq),
                                 LandmarkBound(ix, near_both(8), dp, dq),
                                 LandmarkBound(ix, near_both(16), dp, dq),
                                 StoredBound(ix, parts.view, p, q),
                                 cut};
  tally->walked += walk.path.has_value();
  for (int b = 0; b < kBounds; ++b) {
    if (b == 1) {
      const bool accepted = walk.path && w <= *o1 + bound;
      tally->certified[b] += accepted;
      tally->accepted_wrong += accepted && w > 1.02 * d;
      continue;
    }
    tally->slack[b].push_back((d - lower[b]) / d);
    tally->certified[b] += walk.path && w <= kCertified * lower[b];
  }
}

// Near pairs: a random interior point and one a random walk of 1-24 faces
// away, kept when the O(1) answer is in [lo, hi).
std::pair<Points, Points> DrawPairs(const index::Index& ix, const query::QueryEngine& engine,
                                    bool near, int n) {
  std::mt19937_64 rng(near ? 41 : 42);
  const double lo = near ? engine.scale_length() : engine.l1000();
  const double hi = near ? 3 * engine.scale_length() : 8 * engine.l1000();
  Points a, b;
  for (int tries = 0; tries < 400 && static_cast<int>(a.size()) < n; ++tries) {
    const Points p = AreaUniformPoints(ix, 4 * n, rng()), q = AreaUniformPoints(ix, 4 * n, rng());
    for (size_t i = 0; i < p.size() && static_cast<int>(a.size()) < n; ++i) {
      SurfacePoint other = q[i];
      if (near) {
        int32_t g = p[i].face;
        for (int step = 1 + static_cast<int>(rng() % 24); step > 0; --step) {
          const int32_t twin = ix.twins()[3 * g + static_cast<int32_t>(rng() % 3)];
          if (twin >= 0) g = twin / 3;
        }
        other.face = g;
      }
      const double d = engine.O1Distance(p[i], other);
      if (d >= lo && d < hi) {
        a.push_back(p[i]);
        b.push_back(other);
      }
    }
  }
  return {a, b};
}

double Median(std::vector<double> x) {
  if (x.empty()) return NAN;
  std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
  return x[x.size() / 2];
}

int Run(const std::string& path, int n) {
  absl::StatusOr<std::shared_ptr<const index::Index>> ix = index::Index::Open(path);
  if (!ix.ok()) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), std::string(ix.status().message()).c_str());
    return 1;
  }
  auto engine = query::QueryEngine::Create(*ix);
  if (!engine.ok()) return 1;
  Parts parts(**ix);
  const double faces = (*ix)->num_faces();
  for (const bool near : {true, false}) {
    const auto [a, b] = DrawPairs(**ix, **engine, near, n);
    Tally tally;
    query::QueryScratch scratch;
    for (size_t i = 0; i < a.size(); ++i)
      Measure(**ix, **engine, parts, near, a[i], b[i], scratch, &tally);
    const std::string set = near ? "L-3L (index's L)" : "1-8 L1000";
    for (int bnd = 0; bnd < kBounds; ++bnd) {
      // Bytes a face beyond today's index: k landmark ids and unfolded
      // sources (4 + 8 bytes each) where the bound reads points exactly.
      const int k = bnd == 2 ? 3 : bnd == 3 ? 8 : bnd == 4 ? 16 : 0;
      std::printf(
          "%s\n",
          MarkdownRow(
              {path, set, kBoundNames[bnd], absl::StrFormat("%d", tally.pairs),
               bnd == 1 ? std::string("-")
                        : absl::StrFormat("%.2f%%", 100 * Median(tally.slack[bnd])),
               absl::StrFormat("%.1f%%", 100.0 * tally.certified[bnd] / std::max(1, tally.pairs)),
               bnd == 1 ? absl::StrFormat("%d", tally.accepted_wrong) : std::string("-"),
               absl::StrFormat("%.1f%%", 100.0 * tally.walked / std::max(1, tally.pairs)),
               bnd == 0     ? std::string("0")
               : bnd == kCut ? absl::StrFormat("%.2f", 1e6 * tally.cut_seconds /
                                                          std::max(1, tally.pairs))
                             : std::string("-"),
               k > 0 ? absl::StrFormat("%.1f MiB", faces * k * 12 / (1 << 20)) : std::string("0")})
              .c_str());
    }
  }
  return 0;
}

}  // namespace
}  // namespace geodex::bench

int main(int argc, char** argv) {
  CLI::App app("certificates: lower bounds that certify a near pair's walk");
  std::vector<std::string> indexes;
  int pairs = 400;
  app.add_option("--index", indexes, "Index files")->required();
  app.add_option("--pairs", pairs, "Pairs per set");
  CLI11_PARSE(app, argc, argv);
  std::printf("%s", geodex::bench::MarkdownHeader({"index", "pairs", "bound", "measured",
                                                   "median slack", "walks certified",
                                                   "accepted >2% off", "walked", "us a pair",
                                                   "extra bytes"})
                        .c_str());
  for (const std::string& path : indexes) {
    if (const int code = geodex::bench::Run(path, pairs); code != 0) return code;
  }
  return 0;
}
