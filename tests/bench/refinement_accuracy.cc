#include "tests/bench/refinement_accuracy.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <span>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/internal/bounds/error_bounds.h"
#include "core/query/engine/query_engine.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/bench_timing.h"

namespace geodex::bench {
namespace {

using mesh::SurfacePoint;
using Points = std::vector<SurfacePoint>;

constexpr int kBins = 4;
constexpr const char* kBinNames[kBins] = {"d<L", "L-3L", "3L-10L", ">=10L"};
constexpr double kBinEdges[kBins + 1] = {0, 1, 3, 10, 1e300};

// The index's mesh for the reference engine, as LocalExact rebuilds it.
mesh::Mesh ExactMesh(const index::Index& ix) {
  std::vector<mesh::Vec3> positions(ix.num_vertices());
  for (int32_t v = 0; v < ix.num_vertices(); ++v) {
    positions[v] = {ix.positions()[3 * v], ix.positions()[3 * v + 1], ix.positions()[3 * v + 2]};
  }
  std::vector<mesh::Triangle> faces(ix.num_faces());
  for (int32_t f = 0; f < ix.num_faces(); ++f) {
    faces[f] = {ix.faces()[3 * f], ix.faces()[3 * f + 1], ix.faces()[3 * f + 2]};
  }
  mesh::MeshOptions options;
  options.allow_zero_area_faces = true;
  return *mesh::Mesh::Create(std::move(positions), std::move(faces), "index", options);
}

// Pairs per O(1) scale bin: a random point and one a random walk of 1 to
// 64 faces away (longer walks reach the far bins), at most `per_bin` each.
void DrawBinnedPairs(const index::Index& ix, const query::QueryEngine& engine, bool vertex,
                     int per_bin, Points a[kBins], Points b[kBins]) {
  std::mt19937_64 rng(vertex ? 11 : 12);
  const double scale = engine.scale_length();
  for (int tries = 0; tries < 400 * per_bin; ++tries) {
    const int32_t f = static_cast<int32_t>(rng() % ix.num_faces());
    int32_t g = f;
    for (int step = 1 + static_cast<int>(rng() % 64); step > 0; --step) {
      const int32_t twin = ix.twins()[3 * g + static_cast<int32_t>(rng() % 3)];
      if (twin >= 0) g = twin / 3;
    }
    const SurfacePoint p = RandomPoint(f, vertex, rng), q = RandomPoint(g, vertex, rng);
    const double d = engine.O1Distance(p, q) / scale;
    if (!std::isfinite(d)) continue;
    int bin = 0;
    while (bin + 1 < kBins && d >= kBinEdges[bin + 1]) ++bin;
    if (static_cast<int>(a[bin].size()) < per_bin) {
      a[bin].push_back(p);
      b[bin].push_back(q);
    }
  }
}

// `n` area-uniform interior points.
Points AreaUniformPoints(const mesh::Mesh& m, int n, uint64_t seed) {
  std::vector<double> cumulative(m.num_faces());
  double total = 0;
  for (int32_t f = 0; f < m.num_faces(); ++f) cumulative[f] = total += m.Area(f);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Points out;
  while (static_cast<int>(out.size()) < n) {
    const auto it = std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total);
    const int32_t f = std::min<int32_t>(it - cumulative.begin(), m.num_faces() - 1);
    out.push_back(RandomPoint(f, false, rng));
  }
  return out;
}

double Quantile(std::vector<double> x, double q) {
  if (x.empty()) return NAN;
  std::sort(x.begin(), x.end());
  return x[std::min(x.size() - 1, static_cast<size_t>(q * x.size()))];
}

// One row: the batch's rate, then its answers against the reference.
AccuracyRow Measure(const query::QueryEngine& engine, geodesic::ExactGeodesicSolver& reference,
                    query::QueryScratch& scratch, std::string name,
                    std::span<const SurfacePoint> a, std::span<const SurfacePoint> b,
                    const query::DistanceOptions& options) {
  AccuracyRow row;
  row.pairs = std::move(name);
  row.count = a.size();
  if (a.empty()) return row;
  std::vector<double> out(a.size()), bound(a.size());
  const double start = ThreadCpuSeconds();
  if (!engine.DistanceBatch(a, b, out, options, &scratch, bound).ok()) return row;
  row.rate = a.size() / std::max(ThreadCpuSeconds() - start, 1e-9);
  std::vector<double> errors;
  size_t covered = 0, exact = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    geodesic::GeodesicOptions stop;
    stop.stop_points = {b[i]};
    if (!reference.Propagate({a[i]}, stop).ok()) continue;
    const double d = reference.DistanceAt(b[i]);
    if (!(d > 0) || !std::isfinite(d)) continue;
    const double error = std::abs(out[i] - d);
    errors.push_back(error / d);
    covered += error <= bound[i];
    exact += bound[i] <= query::kExactRelativeBound * out[i];
  }
  row.count = errors.size();
  row.p99 = Quantile(errors, 0.99);
  row.p999 = Quantile(errors, 0.999);
  row.max = errors.empty() ? NAN : *std::max_element(errors.begin(), errors.end());
  row.coverage = static_cast<double>(covered) / std::max<size_t>(errors.size(), 1);
  row.exact_share = static_cast<double>(exact) / std::max<size_t>(errors.size(), 1);
  return row;
}

}  // namespace

SurfacePoint RandomPoint(int32_t face, bool vertex, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  SurfacePoint p{face, {0, 0, 0}};
  if (vertex) {
    p.w[rng() % 3] = 1;
    return p;
  }
  double a = u(rng), b = u(rng);
  if (a + b > 1) a = 1 - a, b = 1 - b;
  p.w = {1 - a - b, a, b};
  return p;
}

std::vector<AccuracyRow> MeasureRefinementAccuracy(std::shared_ptr<const index::Index> ix,
                                                   int per_row) {
  std::vector<AccuracyRow> rows;
  if (ix->accuracy() == nullptr) return rows;
  auto engine = *query::QueryEngine::Create(ix);
  const mesh::Mesh m = ExactMesh(*ix);
  geodesic::ExactGeodesicSolver reference(m);
  // The engine rebuilds its mesh for exact propagation at the first exact
  // answer, and a scratch allocates its solvers at its first: both before
  // the clock runs, so that no row pays for them.
  query::QueryScratch scratch;
  {
    const int32_t twin = ix->twins()[0];
    const SurfacePoint p{0, {1.0 / 3, 1.0 / 3, 1.0 / 3}};
    const SurfacePoint q{twin >= 0 ? twin / 3 : 0, {0.2, 0.3, 0.5}};
    (void)engine->Distance(p, q, {.near_pairs = query::NearPairs::kExact}, &scratch);
  }
  for (const bool vertex : {true, false}) {
    Points a[kBins], b[kBins];
    DrawBinnedPairs(*ix, *engine, vertex, per_row, a, b);
    for (int bin = 0; bin < kBins; ++bin) {
      rows.push_back(
          Measure(*engine, reference, scratch,
                  absl::StrFormat("%s %s", vertex ? "vertex" : "interior", kBinNames[bin]), a[bin],
                  b[bin], {}));
    }
  }
  const Points a = AreaUniformPoints(m, per_row, 21), b = AreaUniformPoints(m, per_row, 22);
  rows.push_back(Measure(*engine, reference, scratch, "uniform", a, b, {}));
  for (const double tolerance : {0.005, 0.001}) {
    rows.push_back(Measure(*engine, reference, scratch,
                           absl::StrFormat("uniform, tolerance %g", tolerance),
                           a, b, {.tolerance = tolerance}));
  }
  return rows;
}

std::string AccuracyHeader() {
  return "\nRefined answers against the exact engine (default mode with bounds, or the "
         "tolerance; O(1) scale bins)\n" +
         MarkdownHeader({"index", "pairs", "count", "pairs/s", "p99", "p99.9", "max",
                         "within bound", "exact"});
}

std::string AccuracyRowText(const std::string& label, const AccuracyRow& row) {
  auto percent = [](double x) { return absl::StrFormat("%.3f%%", 100 * x); };
  return MarkdownRow({label, row.pairs, absl::StrFormat("%zu", row.count),
                      absl::StrFormat("%.0f", row.rate), percent(row.p99), percent(row.p999),
                      percent(row.max), percent(row.coverage), percent(row.exact_share)});
}

}  // namespace geodex::bench
