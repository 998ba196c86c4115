// Query throughput: single-thread queries per second of the constant-time
// engine, next to (a) a gather-only loop that performs just the memory loads a
// query needs (the practical limit) and (b) the paper's linear-interpolation
// baseline (§6.3), all in the same run on the same pairs. Rates are per
// CPU-second of the measuring thread.
//
// The batch runs in the default mode (near and close pairs by path length)
// and in the pure O(1) mode; the share of random pairs that are near is printed with it.
// Vertex and interior pairs/s are single O1Distance calls (O(1)). The
// cost of one near pair in the path and exact modes is measured apart, on
// near pairs drawn on purpose. So is the time of one Path between random
// interior points, traced (O(k)) and with an exact corridor of 8 steps.
//
//   query_bench [--index FILE.gdx]... [--pairs N]
//
// Then, per index with its accuracy calibration, the refinement table: the
// default mode, the pure O(1) mode, the default with error bounds and with
// a tolerance of 0.005, on uniform pairs and on pairs at each scale.
//
// Then the exponential map (core/query/internal/exp_map.h): the time of one map round
// an interior point for radii of 3 L, 10 L and the whole mesh, in the default
// mode and with r from the pure O(1) distance.
//
// Without --index it builds an index of a generated sphere (a note says so).

#include <cstdio>
#include <ctime>
#include <limits>
#include <random>
#include <span>

#include "CLI/CLI.hpp"
#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/mesh/generators.h"
#include "core/query/internal/exp_map.h"
#include "core/query/internal/query_engine.h"
#include "core/query/internal/query_knobs.h"
#include "core/query/internal/unfold_kernel.h"

namespace geodex {
namespace {

// This thread's CPU time: the machines are shared and noisy, and a query is
// single-threaded, so throughput is counted per CPU-second of the measuring
// thread (time the thread spends preempted does not count; cache
// interference from other processes still does).
double ThreadSeconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

std::vector<mesh::SurfacePoint> InteriorPoints(const index::Index& ix, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<mesh::SurfacePoint> out;
  while (static_cast<int>(out.size()) < n) {
    const int32_t f = static_cast<int32_t>(rng() % ix.num_faces());
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    out.push_back({f, {1 - a - b, a, b}});
  }
  return out;
}

std::vector<mesh::SurfacePoint> VertexPoints(const index::Index& ix, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<mesh::SurfacePoint> out;
  while (static_cast<int>(out.size()) < n) {
    const int32_t f = static_cast<int32_t>(rng() % ix.num_faces());
    mesh::SurfacePoint p{f, {0, 0, 0}};
    p.w[rng() % 3] = 1;
    out.push_back(p);
  }
  return out;
}

template <typename F>
double Rate(int64_t n, F&& body) {
  double best = 0;
  for (int rep = 0; rep < 3; ++rep) {
    const double start = ThreadSeconds();
    body();
    const double seconds = ThreadSeconds() - start;
    best = std::max(best, n / seconds);
  }
  return best;
}

// The sample matrix as the index stores it: full, row-major, m x m float32.
struct FullMatrix {
  const index::Index& ix;
  double operator()(int32_t a, int32_t b) const { return ix.SampleDistance(a, b); }
};

// The sample matrix packed as its strict lower triangle, m(m-1)/2 float32:
// the storage alternative, measured here by the same gather loop.
struct PackedMatrix {
  std::vector<float> values;
  explicit PackedMatrix(const index::Index& ix) {
    const int64_t m = ix.num_samples();
    values.reserve(m * (m - 1) / 2);
    for (int64_t a = 1; a < m; ++a) {
      for (int64_t b = 0; b < a; ++b) values.push_back(ix.SampleDistance(a, b));
    }
  }
  double operator()(int32_t a, int32_t b) const {
    if (a == b) return 0;
    if (a < b) std::swap(a, b);
    return values[static_cast<int64_t>(a) * (a - 1) / 2 + b];
  }
};

// The loads of a query: the records and positions of both faces' vertices and
// the 3x3 block of the sample matrix between the two anchors' corners.
template <typename Matrix>
double Gather(const index::Index& ix, const Matrix& matrix, const mesh::SurfacePoint& p,
              const mesh::SurfacePoint& q) {
  const auto faces = ix.faces();
  const auto records = ix.vertices();
  const auto positions = ix.positions();
  double acc = 0;
  const index::VertexRecord* anchor[2];
  const mesh::SurfacePoint* pts[2] = {&p, &q};
  for (int k = 0; k < 2; ++k) {
    const int32_t* f = &faces[3 * pts[k]->face];
    for (int i = 0; i < 3; ++i) {
      acc += records[f[i]].distance[0] + positions[3 * f[i]];
    }
    anchor[k] = &records[f[0]];
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) acc += matrix(anchor[0]->corner[i], anchor[1]->corner[j]);
  }
  return acc;
}

// `count` near pairs (the same or adjacent geodesic triangles), drawn from
// faces close in the file.
std::vector<std::pair<mesh::SurfacePoint, mesh::SurfacePoint>> DrawNearPairs(
    const index::Index& ix, const query::QueryEngine& engine, int count) {
  const auto p = InteriorPoints(ix, 50 * count, 5), q = InteriorPoints(ix, 50 * count, 6);
  std::vector<std::pair<mesh::SurfacePoint, mesh::SurfacePoint>> out;
  for (size_t i = 0; i < p.size() && static_cast<int>(out.size()) < count; ++i) {
    // Meshes are usually stored with neighbouring faces at nearby ids.
    mesh::SurfacePoint near = q[i];
    near.face =
        static_cast<int32_t>((p[i].face + q[i].face % 401 + ix.num_faces() - 200) % ix.num_faces());
    if (engine.IsNearPair(p[i], near)) out.push_back({p[i], near});
  }
  return out;
}

// Microseconds per near pair of Distance in a near-pair mode.
double MicrosecondsPerNearPair(
    const query::QueryEngine& engine, query::NearPairs mode,
    const std::vector<std::pair<mesh::SurfacePoint, mesh::SurfacePoint>>& pairs) {
  query::QueryScratch scratch;
  volatile double sink = 0;
  const double t0 = ThreadSeconds();
  for (const auto& [p, q] : pairs)
    sink = sink + *engine.Distance(p, q, {.near_pairs = mode}, &scratch);
  return 1e6 * (ThreadSeconds() - t0) / std::max<size_t>(1, pairs.size());
}

constexpr int32_t kCorridorSteps = 8;

// Pairs/s of DistanceBatch over `a`, `b` with `options` (and bounds), per
// CPU-second; slow modes run once over at most `cap` pairs.
double BatchRate(const query::QueryEngine& engine, std::span<const mesh::SurfacePoint> a,
                 std::span<const mesh::SurfacePoint> b, const query::DistanceOptions& options,
                 bool bounds, size_t cap) {
  const size_t n = std::min(a.size(), cap);
  if (n == 0) return 0;
  std::vector<double> out(n), bound(bounds ? n : 0);
  query::QueryScratch scratch;
  const int reps = cap < a.size() ? 1 : 3;
  double best = 0;
  for (int rep = 0; rep < reps; ++rep) {
    const double start = ThreadSeconds();
    const absl::Status status =
        engine.DistanceBatch(a.first(n), b.first(n), out, options, &scratch, bound);
    if (!status.ok()) return 0;
    best = std::max(best, n / (ThreadSeconds() - start));
  }
  return best;
}

// The refinement table (DistanceOptions): the default mode, the pure O(1)
// mode, the default with error bounds and a tolerance of 0.005, on
// area-uniform interior pairs and on pairs at each scale (by their O(1)
// distance in units of the scale length L).
void BenchRefinement(const std::string& label, std::shared_ptr<const index::Index> ix, int n) {
  if (ix->accuracy() == nullptr) {
    std::printf("| %s | (no accuracy calibration in the index: run geodex-build calibrate) |\n",
                label.c_str());
    return;
  }
  auto engine = *query::QueryEngine::Create(ix);
  auto traces_only = *query::CreateQueryEngine(ix, {}, {.walk_near_pairs = false});
  const double scale = engine->scale_length();
  const auto a = InteriorPoints(*ix, n, 1), b = InteriorPoints(*ix, n, 2);
  // Pairs at every scale: uniform pairs, and pairs of faces close in the
  // file (meshes usually store neighbouring faces at nearby ids), by bin.
  constexpr double kEdges[] = {0, 1, 3, 10, 1e300};
  const char* const kNames[] = {"d<L", "L-3L", "3L-10L", ">=10L"};
  std::vector<mesh::SurfacePoint> bin_a[4], bin_b[4];
  const auto p = InteriorPoints(*ix, 4 * n, 7), q = InteriorPoints(*ix, 4 * n, 8);
  const size_t per_bin = std::max(1, n / 4);
  for (size_t i = 0; i < p.size(); ++i) {
    mesh::SurfacePoint other = q[i];
    if (i % 2 == 0) {
      const int32_t spread = 1 + static_cast<int32_t>(i % 7) * 50;
      other.face = static_cast<int32_t>(
          (p[i].face + q[i].face % (2 * spread + 1) + ix->num_faces() - spread) % ix->num_faces());
    }
    const double d = engine->O1Distance(p[i], other) / scale;
    int bin = 0;
    while (bin < 3 && d >= kEdges[bin + 1]) ++bin;
    if (bin_a[bin].size() < per_bin) {
      bin_a[bin].push_back(p[i]);
      bin_b[bin].push_back(other);
    }
  }
  // The pure O(1) rate on uniform pairs, the first row's: every row's
  // default rate is also given as a share of it.
  double pure_uniform = 0;
  auto row = [&](const char* name, std::span<const mesh::SurfacePoint> x,
                 std::span<const mesh::SurfacePoint> y) {
    const size_t all = x.size();
    const double def = BatchRate(*engine, x, y, {}, false, all);
    const double pure =
        BatchRate(*engine, x, y, {.near_pairs = query::NearPairs::kUnfold}, false, all);
    const double bounds = BatchRate(*engine, x, y, {}, true, all);
    const double tolerance = BatchRate(*engine, x, y, {.tolerance = 0.005}, true, 300);
    const double traced = BatchRate(*traces_only, x, y, {}, false, all);
    if (pure_uniform == 0) pure_uniform = pure;
    std::printf("| %s | %s | %zu | %.3fM | %.3fM | %.2f | %.2f | %.3fM | %.4fM | %.3fM | %.2f |\n",
                label.c_str(), name, all, def / 1e6, pure / 1e6, def / pure, def / pure_uniform,
                bounds / 1e6, tolerance / 1e6, traced / 1e6, traced / pure);
  };
  row("uniform", a, b);
  for (int bin = 0; bin < 4; ++bin) row(kNames[bin], bin_a[bin], bin_b[bin]);
}

void Bench(const std::string& label, std::shared_ptr<const index::Index> ix, int n) {
  auto engine = *query::QueryEngine::Create(ix);
  const auto a = InteriorPoints(*ix, n, 1), b = InteriorPoints(*ix, n, 2);
  const auto va = VertexPoints(*ix, n, 3), vb = VertexPoints(*ix, n, 4);
  std::vector<double> out(n);
  volatile double sink = 0;
  const double vertex_rate = Rate(n, [&] {
    for (int i = 0; i < n; ++i) out[i] = engine->O1Distance(va[i], vb[i]);
    sink = sink + out[n - 1];
  });
  const double interior_rate = Rate(n, [&] {
    for (int i = 0; i < n; ++i) out[i] = engine->O1Distance(a[i], b[i]);
    sink = sink + out[n - 1];
  });
  const double batch_rate = Rate(n, [&] {
    (void)engine->DistanceBatch(a, b, out);
    sink = sink + out[n - 1];
  });
  const double unfold_batch_rate = Rate(n, [&] {
    (void)engine->DistanceBatch(a, b, out, {.near_pairs = query::NearPairs::kUnfold});
    sink = sink + out[n - 1];
  });
  int near = 0;
  for (int i = 0; i < n; ++i) near += engine->IsNearPair(a[i], b[i]);
  auto scalar_engine = *query::CreateQueryEngine(ix, {}, {.vector_lanes = false});
  const double scalar_batch_rate = Rate(n, [&] {
    (void)scalar_engine->DistanceBatch(a, b, out);
    sink = sink + out[n - 1];
  });
  const double gather_rate = Rate(n, [&] {
    double acc = 0;
    for (int i = 0; i < n; ++i) acc += Gather(*ix, FullMatrix{*ix}, a[i], b[i]);
    sink = sink + acc;
  });
  const PackedMatrix packed(*ix);
  const double packed_gather_rate = Rate(n, [&] {
    double acc = 0;
    for (int i = 0; i < n; ++i) acc += Gather(*ix, packed, a[i], b[i]);
    sink = sink + acc;
  });
  const double linear_rate = Rate(n, [&] {
    double acc = 0;
    for (int i = 0; i < n; ++i) acc += engine->LinearInterpolationDistance(a[i], b[i]);
    sink = sink + acc;
  });
  // Paths between random interior points, traced (O(k)) and with the exact
  // corridor.
  const int num_paths = std::min(n, 100);
  double path_ms[2];
  for (int e = 0; e < 2; ++e) {
    const double t0 = ThreadSeconds();
    size_t points = 0;
    for (int i = 0; i < num_paths; ++i)
      points += engine->Path(a[i], b[i], e ? kCorridorSteps : 0)->size();
    path_ms[e] = 1e3 * (ThreadSeconds() - t0) / num_paths;
    sink = sink + static_cast<double>(points);
  }
  const auto near_pairs = DrawNearPairs(*ix, *engine, 1000);
  const double path_us = MicrosecondsPerNearPair(*engine, query::NearPairs::kPath, near_pairs);
  const double exact_us = MicrosecondsPerNearPair(*engine, query::NearPairs::kExact, near_pairs);
  const double m = ix->num_samples();
  std::printf(
      "| %s | %d | %d | %.2fM | %.2fM | %.2fM | %.2fM (%.2f%% near) | %.2fM | %.2fM | %.2f | "
      "%.2fM | %.1f / %.1f us (%zu) | %.2f / %.2f ms | %.2fM (%.1f / %.1f MiB) |\n",
      label.c_str(), ix->num_vertices(), ix->num_samples(), vertex_rate / 1e6, interior_rate / 1e6,
      batch_rate / 1e6, unfold_batch_rate / 1e6, 100.0 * near / n, scalar_batch_rate / 1e6,
      gather_rate / 1e6, gather_rate / batch_rate, linear_rate / 1e6, path_us, exact_us,
      near_pairs.size(), path_ms[0], path_ms[1], packed_gather_rate / 1e6, m * m * 4 / (1 << 20),
      m * (m - 1) / 2 * 4 / (1 << 20));
}

void BenchExpMap(const std::string& label, std::shared_ptr<const index::Index> ix) {
  auto engine = *query::QueryEngine::Create(ix);
  const auto centres = InteriorPoints(*ix, 5, 7);
  const double l = engine->scale_length();
  for (const double radius : {3 * l, 10 * l, std::numeric_limits<double>::max()}) {
    double ms[2];
    size_t mapped = 0;
    for (int mode = 0; mode < 2; ++mode) {
      query::ExpMapOptions options;
      options.radius = radius;
      if (mode == 1) options.distance.near_pairs = query::NearPairs::kUnfold;
      query::QueryScratch scratch;
      (void)query::ExpMap(*engine, centres[0], options, &scratch);  // the lazy exact mesh
      mapped = 0;
      const double t0 = ThreadSeconds();
      for (const mesh::SurfacePoint& c : centres) {
        mapped += query::ExpMap(*engine, c, options, &scratch)->size();
      }
      ms[mode] = 1e3 * (ThreadSeconds() - t0) / centres.size();
    }
    const double per_map = static_cast<double>(mapped) / centres.size();
    const std::string scale = radius == std::numeric_limits<double>::max()
                                  ? "whole mesh"
                                  : absl::StrFormat("%.0f L", radius / l);
    std::printf("| %s | %s | %.0f | %.2f ms | %.2f ms | %.2f us |\n", label.c_str(), scale.c_str(),
                per_map, ms[0], ms[1], 1e3 * ms[0] / per_map);
  }
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app{"query_bench: constant-time query throughput, one thread."};
  std::vector<std::string> indexes;
  int pairs = 1'000'000;
  app.add_option("--index", indexes, "Index files to measure");
  app.add_option("--pairs", pairs, "Pairs per measurement");
  bool expmap_only = false;
  app.add_flag("--expmap-only", expmap_only, "Only the exponential map table");
  CLI11_PARSE(app, argc, argv);
  std::printf("(batch: far pairs %s)\n", geodex::query::kernel::HasAvx2Lanes()
                                             ? "four at a time with AVX2"
                                             : "one at a time: no AVX2 in this build or CPU");
  std::printf(
      "| index | vertices | m | vertex pairs/s | interior pairs/s | batch (validated) pairs/s | "
      "batch, pure O(1)/s (near share) | batch, one pair at a time/s | gather-only/s | "
      "gather/batch | linear baseline/s | one near pair: path / exact mode (pairs) | "
      "one path: traced / exact corridor | gather-only, packed matrix/s (full / packed size) |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  if (indexes.empty()) {
    std::printf("(no --index given: a generated sphere, m = 500)\n");
    geodex::builder::BuildOptions options;
    options.num_samples = 500;
    geodex::builder::BuildSummary summary;
    auto data = geodex::builder::BuildIndex(geodex::mesh::gen::Sphere(5, 1.0), options, &summary);
    auto ix = geodex::index::Index::FromBytes(*geodex::index::SerializeIndex(*data));
    geodex::Bench("sphere(5)", *ix, pairs);
    std::printf(
        "\n| index | radius | vertices mapped | one map, default | one map, pure O(1) | "
        "per vertex, default |\n|---|---|---|---|---|---|\n");
    geodex::BenchExpMap("sphere(5)", *ix);
    return 0;
  }
  std::vector<std::shared_ptr<const geodex::index::Index>> loaded;
  for (const std::string& path : indexes) {
    auto ix = geodex::index::Index::Open(path);
    if (!ix.ok()) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), ix.status().ToString().c_str());
      return 1;
    }
    loaded.push_back(*ix);
    if (!expmap_only) geodex::Bench(path, *ix, pairs);
  }
  std::printf(
      "\nRefinement (DistanceOptions), batch pairs/s; tolerance: at most 300 pairs, once\n"
      "| index | pairs | count | default/s | pure O(1)/s | default / pure | default / pure "
      "uniform | default + bounds/s | tolerance 0.005/s | default, traces only (no walk)/s | "
      "traces only / pure |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (size_t i = 0; i < loaded.size() && !expmap_only; ++i) {
    geodex::BenchRefinement(indexes[i], loaded[i], std::min(pairs, 200'000));
  }
  std::printf(
      "\nExponential map (5 interior centres)\n| index | radius | vertices mapped | "
      "one map, default | one map, pure O(1) | per vertex, default |\n"
      "|---|---|---|---|---|---|\n");
  for (size_t i = 0; i < loaded.size(); ++i) geodex::BenchExpMap(indexes[i], loaded[i]);
  return 0;
}
