#include "tests/bench/query_bench_lib.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <random>
#include <span>
#include <utility>

#include "Eigen/Geometry"
#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/common/status_macros.h"
#include "core/mesh/generators.h"
#include "core/query/input_queries.h"
#include "core/query/engine/query_engine.h"
#include "core/query/engine/query_knobs.h"
#include "core/query/engine/internal/o1/unfold_kernel.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/bench_timing.h"
#include "tests/bench/near_profile.h"
#include "tests/bench/refinement_accuracy.h"

namespace geodex::bench {
namespace {

using Points = std::vector<mesh::SurfacePoint>;
using PointPairs = std::vector<std::pair<mesh::SurfacePoint, mesh::SurfacePoint>>;

constexpr int32_t kCorridorSteps = 8;

// The best of three runs of `body`, which handles `n` pairs.
template <typename F>
double Rate(int64_t n, F&& body) {
  double best = 0;
  for (int rep = 0; rep < 3; ++rep) {
    const double start = ThreadCpuSeconds();
    body();
    const double seconds = ThreadCpuSeconds() - start;
    best = std::max(best, n / seconds);
  }
  return best;
}

// The sample matrix as the index stores it: full, row-major, m x m float32.
struct FullMatrix {
  const index::Index& ix;
  double operator()(int32_t a, int32_t b) const { return ix.SampleDistance(a, b); }
};

// The loads of a query: the records and positions of both faces' vertices,
// the anchors' triangles and the 3x3 block of the sample matrix between their
// corners.
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
  if (anchor[0]->triangle < 0 || anchor[1]->triangle < 0) return acc;
  const auto triangles = ix.triangles();
  const int32_t* c0 = triangles[anchor[0]->triangle].corner;
  const int32_t* c1 = triangles[anchor[1]->triangle].corner;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) acc += matrix(c0[i], c1[j]);
  }
  return acc;
}

// `count` near pairs (the same or adjacent geodesic triangles), drawn from
// faces close in the file.
PointPairs DrawNearPairs(const index::Index& ix, const query::QueryEngine& engine, int count) {
  const auto p = InteriorPoints(ix, 50 * count, 5), q = InteriorPoints(ix, 50 * count, 6);
  PointPairs out;
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
double MicrosecondsPerNearPair(const query::QueryEngine& engine, query::NearPairs mode,
                               const PointPairs& pairs) {
  query::QueryScratch scratch;
  volatile double sink = 0;
  const double t0 = ThreadCpuSeconds();
  for (const auto& [p, q] : pairs)
    sink = sink + *engine.Distance(p, q, {.near_pairs = mode}, &scratch);
  return 1e6 * (ThreadCpuSeconds() - t0) / std::max<size_t>(1, pairs.size());
}

// The single-call and batch rates of the first table, and the near share.
void MeasureQueryRates(std::shared_ptr<const index::Index> ix, const query::QueryEngine& engine,
                       const Points& a, const Points& b, ThroughputFigures* f) {
  const int n = static_cast<int>(a.size());
  const auto va = VertexPoints(*ix, n, 3), vb = VertexPoints(*ix, n, 4);
  std::vector<double> out(n);
  volatile double sink = 0;
  f->vertex_rate = Rate(n, [&] {
    for (int i = 0; i < n; ++i) out[i] = engine.O1Distance(va[i], vb[i]);
    sink = sink + out[n - 1];
  });
  f->interior_rate = Rate(n, [&] {
    for (int i = 0; i < n; ++i) out[i] = engine.O1Distance(a[i], b[i]);
    sink = sink + out[n - 1];
  });
  f->batch_rate = Rate(n, [&] {
    (void)engine.DistanceBatch(a, b, out);
    sink = sink + out[n - 1];
  });
  f->unfold_batch_rate = Rate(n, [&] {
    (void)engine.DistanceBatch(a, b, out, {.near_pairs = query::NearPairs::kUnfold});
    sink = sink + out[n - 1];
  });
  int near = 0;
  for (int i = 0; i < n; ++i) near += engine.IsNearPair(a[i], b[i]);
  f->near_percent = 100.0 * near / n;
  auto scalar_engine = *query::CreateQueryEngine(ix, {}, {.vector_lanes = false});
  f->scalar_batch_rate = Rate(n, [&] {
    (void)scalar_engine->DistanceBatch(a, b, out);
    sink = sink + out[n - 1];
  });
}

// The gather-only loops (full and packed matrix) and the linear baseline.
void MeasureGatherRates(const index::Index& ix, const query::QueryEngine& engine, const Points& a,
                        const Points& b, ThroughputFigures* f) {
  const int n = static_cast<int>(a.size());
  volatile double sink = 0;
  f->gather_rate = Rate(n, [&] {
    double acc = 0;
    for (int i = 0; i < n; ++i) acc += Gather(ix, FullMatrix{ix}, a[i], b[i]);
    sink = sink + acc;
  });
  const PackedMatrix packed(ix);
  f->packed_gather_rate = Rate(n, [&] {
    double acc = 0;
    for (int i = 0; i < n; ++i) acc += Gather(ix, packed, a[i], b[i]);
    sink = sink + acc;
  });
  f->linear_rate = Rate(n, [&] {
    double acc = 0;
    for (int i = 0; i < n; ++i) acc += engine.LinearInterpolationDistance(a[i], b[i]);
    sink = sink + acc;
  });
}

// Paths between random interior points, traced (O(k)) and with the exact
// corridor, and one near pair in the path and exact modes.
void MeasurePaths(const index::Index& ix, const query::QueryEngine& engine, const Points& a,
                  const Points& b, ThroughputFigures* f) {
  volatile double sink = 0;
  const int num_paths = std::min(static_cast<int>(a.size()), 100);
  double path_ms[2];
  for (int e = 0; e < 2; ++e) {
    const double t0 = ThreadCpuSeconds();
    size_t points = 0;
    for (int i = 0; i < num_paths; ++i)
      points += engine.Path(a[i], b[i], e ? kCorridorSteps : 0)->size();
    path_ms[e] = 1e3 * (ThreadCpuSeconds() - t0) / num_paths;
    sink = sink + static_cast<double>(points);
  }
  f->path_ms = path_ms[0];
  f->corridor_ms = path_ms[1];
  const PointPairs near_pairs = DrawNearPairs(ix, engine, 1000);
  f->near_path_us = MicrosecondsPerNearPair(engine, query::NearPairs::kPath, near_pairs);
  f->near_exact_us = MicrosecondsPerNearPair(engine, query::NearPairs::kExact, near_pairs);
  f->near_pairs = near_pairs.size();
}

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
    const double start = ThreadCpuSeconds();
    const absl::Status status =
        engine.DistanceBatch(a.first(n), b.first(n), out, options, &scratch, bound);
    if (!status.ok()) return 0;
    best = std::max(best, n / (ThreadCpuSeconds() - start));
  }
  return best;
}

// Pairs at every scale: uniform pairs, and pairs of faces close in the file
// (meshes usually store neighbouring faces at nearby ids), by their O(1)
// distance in units of the scale length L, at most n / 4 per bin.
constexpr int kScaleBins = 4;
constexpr const char* kScaleBinNames[kScaleBins] = {"d<L", "L-3L", "3L-10L", ">=10L"};

struct ScaleBins {
  Points a[kScaleBins], b[kScaleBins];
};

ScaleBins DrawScalePairs(const index::Index& ix, const query::QueryEngine& engine, int n) {
  constexpr double kEdges[] = {0, 1, 3, 10, 1e300};
  const double scale = engine.scale_length();
  ScaleBins bins;
  const auto p = InteriorPoints(ix, 4 * n, 7), q = InteriorPoints(ix, 4 * n, 8);
  const size_t per_bin = std::max(1, n / 4);
  for (size_t i = 0; i < p.size(); ++i) {
    mesh::SurfacePoint other = q[i];
    if (i % 2 == 0) {
      const int32_t spread = 1 + static_cast<int32_t>(i % 7) * 50;
      other.face = static_cast<int32_t>(
          (p[i].face + q[i].face % (2 * spread + 1) + ix.num_faces() - spread) % ix.num_faces());
    }
    const double d = engine.O1Distance(p[i], other) / scale;
    int bin = 0;
    while (bin < kScaleBins - 1 && d >= kEdges[bin + 1]) ++bin;
    if (bins.a[bin].size() < per_bin) {
      bins.a[bin].push_back(p[i]);
      bins.b[bin].push_back(other);
    }
  }
  return bins;
}

// True when `ix` carries its accuracy calibration; else prints a note row
// for `label` saying so.
bool Calibrated(const std::string& label, const index::Index& ix) {
  if (ix.accuracy() != nullptr) return true;
  std::printf("| %s | (no accuracy calibration in the index: run geodex-build calibrate) |\n",
              label.c_str());
  return false;
}

// One refinement row's rates on the pairs `x`, `y`.
RefinementFigures MeasureRefinement(const query::QueryEngine& engine,
                                    const query::QueryEngine& traces_only, const char* name,
                                    std::span<const mesh::SurfacePoint> x,
                                    std::span<const mesh::SurfacePoint> y) {
  const size_t all = x.size();
  RefinementFigures f;
  f.pairs = name;
  f.count = all;
  f.default_rate = BatchRate(engine, x, y, {}, false, all);
  f.pure_rate = BatchRate(engine, x, y, {.near_pairs = query::NearPairs::kUnfold}, false, all);
  f.bounds_rate = BatchRate(engine, x, y, {}, true, all);
  f.tolerance_rate = BatchRate(engine, x, y, {.tolerance = 0.005}, true, 300);
  f.traced_rate = BatchRate(traces_only, x, y, {}, false, all);
  return f;
}

// The throughput row, then the registered tables and the distance fields, of
// a sphere built here.
int RunOnGeneratedSphere(int pairs) {
  std::printf("(no --index given: a generated sphere, m = 500)\n");
  builder::BuildOptions options;
  options.num_samples = 500;
  builder::BuildSummary summary;
  auto data = builder::BuildIndex(mesh::gen::Sphere(5, 1.0), options, &summary);
  auto ix = index::Index::FromBytes(*index::SerializeIndex(*data));
  std::printf("%s\n", ThroughputRow("sphere(5)", MeasureThroughput(*ix, pairs)).c_str());
  for (const QueryBenchTable* table : QueryBenchTables()) {
    std::printf("\n%s", table->header().c_str());
    table->run("sphere(5)", *ix);
  }
  std::printf("\nDistance fields (5 interior sources, one at a time)\n%s", FieldHeader().c_str());
  if (const absl::Status status = BenchField("sphere(5)", *ix); !status.ok()) {
    std::fprintf(stderr, "sphere(5): %s\n", status.ToString().c_str());
    return 1;
  }
  return 0;
}

}  // namespace

std::unique_ptr<CLI::App> QueryBenchFlags(QueryBenchOptions* options) {
  auto app = std::make_unique<CLI::App>("query_bench: constant-time query throughput, one thread.");
  app->add_option("--index", options->indexes, "Index files to measure");
  app->add_option("--pairs", options->pairs, "Pairs per measurement");
  for (const QueryBenchTable* table : QueryBenchTables()) {
    app->add_flag("--" + table->flag + "-only", options->table_only[table->flag], table->help);
  }
  app->add_flag("--field-only", options->field_only, "Only the distance field table");
  app->add_option("--accuracy-pairs", options->accuracy_pairs,
                  "Pairs per row of the table against the exact engine");
  app->add_flag("--near-profile", options->near_profile,
                "Only the near pairs' rates and where their time goes (with --every-distance: "
                "where the every-distance mode's time goes, on its area-uniform pairs)");
  app->add_option("--every-distance", options->every_distance,
                  "Only the every-distance table: area-uniform pairs, default mode with the "
                  "refinement threshold raised to X L1000, against default and pure O(1)")
      ->check(CLI::PositiveNumber);
  return app;
}

std::vector<mesh::SurfacePoint> InteriorPoints(const index::Index& ix, int n, uint64_t seed) {
  return InteriorPoints(ix.num_faces(), n, seed);
}

std::vector<mesh::SurfacePoint> InteriorPoints(int32_t num_faces, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<mesh::SurfacePoint> out;
  while (static_cast<int>(out.size()) < n) {
    const int32_t f = static_cast<int32_t>(rng() % num_faces);
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

PackedMatrix::PackedMatrix(const index::Index& ix) {
  const int64_t m = ix.num_samples();
  values_.reserve(m * (m - 1) / 2);
  for (int64_t a = 1; a < m; ++a) {
    for (int64_t b = 0; b < a; ++b) values_.push_back(ix.SampleDistance(a, b));
  }
}

double PackedMatrix::operator()(int32_t a, int32_t b) const {
  if (a == b) return 0;
  if (a < b) std::swap(a, b);
  return values_[static_cast<int64_t>(a) * (a - 1) / 2 + b];
}

ThroughputFigures MeasureThroughput(std::shared_ptr<const index::Index> ix, int n) {
  auto engine = *query::QueryEngine::Create(ix);
  ThroughputFigures f;
  f.vertices = ix->num_vertices();
  f.samples = ix->num_samples();
  const Points a = InteriorPoints(*ix, n, 1), b = InteriorPoints(*ix, n, 2);
  MeasureQueryRates(ix, *engine, a, b, &f);
  MeasureGatherRates(*ix, *engine, a, b, &f);
  MeasurePaths(*ix, *engine, a, b, &f);
  return f;
}

std::string ThroughputHeader() {
  return MarkdownHeader(
      {"index", "vertices", "m", "vertex pairs/s", "interior pairs/s", "batch (validated) pairs/s",
       "batch, pure O(1)/s (near share)", "batch, one pair at a time/s", "gather-only/s",
       "gather/batch", "linear baseline/s", "one near pair: path / exact mode (pairs)",
       "one path: traced / exact corridor", "gather-only, packed matrix/s (full / packed size)"});
}

std::string ThroughputRow(const std::string& label, const ThroughputFigures& f) {
  const double m = f.samples;
  auto millions = [](double rate) { return absl::StrFormat("%.2fM", rate / 1e6); };
  return MarkdownRow({
      label,
      absl::StrFormat("%d", f.vertices),
      absl::StrFormat("%d", f.samples),
      millions(f.vertex_rate),
      millions(f.interior_rate),
      millions(f.batch_rate),
      absl::StrFormat("%.2fM (%.2f%% near)", f.unfold_batch_rate / 1e6, f.near_percent),
      millions(f.scalar_batch_rate),
      millions(f.gather_rate),
      absl::StrFormat("%.2f", f.gather_rate / f.batch_rate),
      millions(f.linear_rate),
      absl::StrFormat("%.1f / %.1f us (%zu)", f.near_path_us, f.near_exact_us, f.near_pairs),
      absl::StrFormat("%.2f / %.2f ms", f.path_ms, f.corridor_ms),
      absl::StrFormat("%.2fM (%.1f / %.1f MiB)", f.packed_gather_rate / 1e6, m * m * 4 / (1 << 20),
                      m * (m - 1) / 2 * 4 / (1 << 20)),
  });
}

void BenchRefinement(const std::string& label, std::shared_ptr<const index::Index> ix, int n) {
  if (!Calibrated(label, *ix)) return;
  auto engine = *query::QueryEngine::Create(ix);
  auto traces_only = *query::CreateQueryEngine(ix, {}, {.walk_near_pairs = false});
  const auto a = InteriorPoints(*ix, n, 1), b = InteriorPoints(*ix, n, 2);
  const ScaleBins bins = DrawScalePairs(*ix, *engine, n);
  // Every row's default rate is also given as a share of the pure O(1) rate
  // on uniform pairs, the first row's.
  double pure_uniform = 0;
  for (int row = -1; row < kScaleBins; ++row) {
    RefinementFigures f = row < 0 ? MeasureRefinement(*engine, *traces_only, "uniform", a, b)
                                  : MeasureRefinement(*engine, *traces_only, kScaleBinNames[row],
                                                      bins.a[row], bins.b[row]);
    if (pure_uniform == 0) pure_uniform = f.pure_rate;
    f.pure_uniform_rate = pure_uniform;
    std::printf("%s\n", RefinementRow(label, f).c_str());
  }
}

std::string RefinementHeader() {
  return "\nRefinement (DistanceOptions), batch pairs/s; tolerance: at most 300 pairs, once\n" +
         MarkdownHeader({"index", "pairs", "count", "default/s", "pure O(1)/s", "default / pure",
                         "default / pure uniform", "default + bounds/s", "tolerance 0.005/s",
                         "default, traces only (no walk)/s", "traces only / pure"});
}

std::string RefinementRow(const std::string& label, const RefinementFigures& f) {
  return MarkdownRow({
      label,
      f.pairs,
      absl::StrFormat("%zu", f.count),
      absl::StrFormat("%.3fM", f.default_rate / 1e6),
      absl::StrFormat("%.3fM", f.pure_rate / 1e6),
      absl::StrFormat("%.2f", f.default_rate / f.pure_rate),
      absl::StrFormat("%.2f", f.default_rate / f.pure_uniform_rate),
      absl::StrFormat("%.3fM", f.bounds_rate / 1e6),
      absl::StrFormat("%.4fM", f.tolerance_rate / 1e6),
      absl::StrFormat("%.3fM", f.traced_rate / 1e6),
      absl::StrFormat("%.2f", f.traced_rate / f.pure_rate),
  });
}

absl::Status BenchField(const std::string& label, std::shared_ptr<const index::Index> ix) {
  GEODEX_ASSIGN_OR_RETURN(auto queries, query::InputQueries::Create(ix));
  // Points of the mesh file's faces: the facade's ids, which differ from the
  // index's where the builder split long edges or repaired the mesh.
  const auto sources = InteriorPoints(queries->num_faces(), 5, 8);
  std::vector<query::EnginePoints> read(sources.size());
  for (size_t i = 0; i < sources.size(); ++i) {
    GEODEX_RETURN_IF_ERROR(queries->Read(std::span(&sources[i], 1), query::Named("source"), &read[i]));
  }
  const double l = queries->scale_length();
  query::QueryScratch scratch;
  // The lazy exact mesh and the scratch's solver, made before the clock runs.
  GEODEX_RETURN_IF_ERROR(queries->FieldWithin(read[0], {.radius = l}, &scratch).status());
  const double kWhole = std::numeric_limits<double>::max();
  for (const double radius : {3 * l, 10 * l, 0.0, kWhole}) {
    size_t vertices = 0;
    const double t0 = ThreadCpuSeconds();
    for (const query::EnginePoints& source : read) {
      if (radius == 0) {
        GEODEX_ASSIGN_OR_RETURN(const query::DistanceField field, queries->Field(source));
        vertices += field.distance.size();
      } else {
        GEODEX_ASSIGN_OR_RETURN(const query::RadiusField field,
                                queries->FieldWithin(source, {.radius = radius}, &scratch));
        vertices += field.vertices.size();
      }
    }
    FieldFigures f;
    f.us = 1e6 * (ThreadCpuSeconds() - t0) / read.size();
    f.field = radius == 0        ? "whole mesh, O(1)"
              : radius == kWhole ? "whole mesh, exact"
                                 : absl::StrFormat("%.0f L", radius / l);
    f.per_field = static_cast<double>(vertices) / read.size();
    std::printf("%s\n", FieldRow(label, f).c_str());
  }
  return absl::OkStatus();
}

std::string FieldHeader() {
  return MarkdownHeader({"index", "field", "vertices", "one field", "vertices/s"});
}

std::string FieldRow(const std::string& label, const FieldFigures& f) {
  return MarkdownRow({label, f.field, absl::StrFormat("%.0f", f.per_field),
                      absl::StrFormat("%.0f us", f.us),
                      absl::StrFormat("%.3gM", f.us > 0 ? f.per_field / f.us : 0)});
}

void BenchNearProfile(const std::string& label, std::shared_ptr<const index::Index> ix, int n) {
  if (!Calibrated(label, *ix)) return;
  auto engine = *query::QueryEngine::Create(ix);
  const ScaleBins bins = DrawScalePairs(*ix, *engine, n);
  const Points &x = bins.a[1], &y = bins.b[1];
  const size_t all = x.size();
  const double near_rate = BatchRate(*engine, bins.a[0], bins.b[0], {}, false, bins.a[0].size());
  const double default_rate = BatchRate(*engine, x, y, {}, false, all);
  const double pure_rate =
      BatchRate(*engine, x, y, {.near_pairs = query::NearPairs::kUnfold}, false, all);
  PrintProfileRows(label, *engine, x, y, {},
                   absl::StrFormat("all (d<L %.3fM/s, L-3L %.3fM/s, pure O(1) %.3fM/s)",
                                   near_rate / 1e6, default_rate / 1e6, pure_rate / 1e6));
}

namespace {

std::vector<QueryBenchTable>& Registry() {
  static auto* const tables = new std::vector<QueryBenchTable>;
  return *tables;
}

}  // namespace

bool RegisterQueryBenchTable(QueryBenchTable table) {
  Registry().push_back(std::move(table));
  return true;
}

std::vector<const QueryBenchTable*> QueryBenchTables() {
  std::vector<const QueryBenchTable*> out;
  for (const QueryBenchTable& table : Registry()) out.push_back(&table);
  std::sort(out.begin(), out.end(),
            [](const QueryBenchTable* a, const QueryBenchTable* b) { return a->flag < b->flag; });
  return out;
}

// `n` interior points drawn uniformly by area: a face with probability
// proportional to its area, uniform barycentric weights.
std::vector<mesh::SurfacePoint> AreaUniformPoints(const index::Index& ix, int n, uint64_t seed) {
  const auto pos = ix.positions();
  const auto faces = ix.faces();
  std::vector<double> cumulative(ix.num_faces());
  double total = 0;
  for (int32_t f = 0; f < ix.num_faces(); ++f) {
    Eigen::Vector3d c[3];
    for (int k = 0; k < 3; ++k) {
      const int32_t v = faces[3 * f + k];
      c[k] = {pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]};
    }
    total += (c[1] - c[0]).cross(c[2] - c[0]).norm();
    cumulative[f] = total;
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<mesh::SurfacePoint> out;
  while (static_cast<int>(out.size()) < n) {
    const double at = u(rng) * total;
    const int32_t f = static_cast<int32_t>(
        std::min<ptrdiff_t>(std::upper_bound(cumulative.begin(), cumulative.end(), at) -
                                cumulative.begin(),
                            ix.num_faces() - 1));
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    out.push_back({f, {1 - a - b, a, b}});
  }
  return out;
}

// The every-distance table's row of one index: area-uniform interior pairs,
// the default mode with the threshold raised to `below` L1000, beside the
// default and the pure O(1) answer on the same pairs; how many of the raised
// pairs kept their O(1) answer.
void BenchEveryDistance(const std::string& label, std::shared_ptr<const index::Index> ix,
                        double below, int pairs) {
  auto engine = query::QueryEngine::Create(ix);
  if (!engine.ok()) {
    std::printf("| %s | %s |\n", label.c_str(), engine.status().ToString().c_str());
    return;
  }
  const auto a = AreaUniformPoints(*ix, pairs, 21), b = AreaUniformPoints(*ix, pairs, 22);
  const size_t n = a.size();
  std::vector<double> out(n);
  auto rate = [&](const query::DistanceOptions& options, query::NearPairStats* stats) {
    query::QueryScratch scratch;
    const double start = ThreadCpuSeconds();
    if (!(*engine)->DistanceBatch(a, b, out, options, &scratch).ok()) return 0.0;
    const double seconds = ThreadCpuSeconds() - start;
    if (stats != nullptr) *stats = scratch.near_pair_stats();
    return n / seconds;
  };
  const double pure = rate({.near_pairs = query::NearPairs::kUnfold}, nullptr);
  const double plain = rate({}, nullptr);
  query::NearPairStats stats;
  const double every = rate({.refine_below_l1000 = below}, &stats);
  std::printf("%s\n", MarkdownRow({label, absl::StrFormat("%zu", n),
                                   absl::StrFormat("%.3fM", pure / 1e6),
                                   absl::StrFormat("%.3fM", plain / 1e6),
                                   absl::StrFormat("%.1fK", every / 1e3),
                                   absl::StrFormat("%.1f%%", 100.0 * stats.pairs / n),
                                   absl::StrFormat("%.2f%%", 100.0 * stats.exact_solves / n),
                                   absl::StrFormat("%.2f%%", 100.0 * stats.raised_kept / n)})
                          .c_str());
}

void BenchEveryDistanceProfile(const std::string& label, std::shared_ptr<const index::Index> ix,
                               double below, int n) {
  auto engine = *query::QueryEngine::Create(ix);
  const auto a = AreaUniformPoints(*ix, n, 21), b = AreaUniformPoints(*ix, n, 22);
  PrintProfileRows(label, *engine, a, b, {.refine_below_l1000 = below},
                   absl::StrFormat("all area-uniform pairs, threshold %g L1000", below));
}

int RunQueryBench(const QueryBenchOptions& options) {
  if (options.every_distance > 0) {
    std::printf("Every distance: area-uniform interior pairs, batch pairs/s, one thread; "
                "threshold %g L1000\n%s",
                options.every_distance,
                MarkdownHeader({"index", "pairs", "pure O(1)/s", "default/s", "every-distance/s",
                                "refined (walked or exact)", "exact", "O(1) kept"})
                    .c_str());
    for (const std::string& path : options.indexes) {
      auto ix = index::Index::Open(path);
      if (!ix.ok()) {
        std::fprintf(stderr, "%s\n", ix.status().ToString().c_str());
        return 1;
      }
      BenchEveryDistance(path, *ix, options.every_distance, options.pairs);
      if (options.near_profile) {
        std::printf("%s", NearProfileHeader("The every-distance mode's area-uniform pairs").c_str());
        BenchEveryDistanceProfile(path, *ix, options.every_distance, options.pairs);
      }
    }
    return 0;
  }
  std::printf("(batch: far pairs %s)\n", query::kernel::HasAvx2Lanes()
                                             ? "four at a time with AVX2"
                                             : "one at a time: no AVX2 in this build or CPU");
  if (!options.near_profile) std::printf("%s", ThroughputHeader().c_str());
  if (options.indexes.empty()) return RunOnGeneratedSphere(options.pairs);
  // A --<table>-only option (or --field-only) leaves out every other table.
  const auto only = [&](const std::string& flag) {
    const auto it = options.table_only.find(flag);
    return it != options.table_only.end() && it->second;
  };
  bool some_only = options.field_only;
  for (const QueryBenchTable* table : QueryBenchTables()) some_only |= only(table->flag);
  std::vector<std::shared_ptr<const index::Index>> loaded;
  for (const std::string& path : options.indexes) {
    auto ix = index::Index::Open(path);
    if (!ix.ok()) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), ix.status().ToString().c_str());
      return 1;
    }
    loaded.push_back(*ix);
    if (options.near_profile) {
      if (loaded.size() == 1) {
        std::printf("%s", NearProfileHeader("Near pairs at L-3L of the O(1) answer").c_str());
      }
      BenchNearProfile(path, *ix, std::min(options.pairs, 200'000));
      continue;
    }
    if (!some_only) {
      std::printf("%s\n", ThroughputRow(path, MeasureThroughput(*ix, options.pairs)).c_str());
    }
  }
  if (options.near_profile) return 0;
  if (!some_only) {
    std::printf("%s", RefinementHeader().c_str());
    for (size_t i = 0; i < loaded.size(); ++i) {
      BenchRefinement(options.indexes[i], loaded[i], std::min(options.pairs, 200'000));
    }
    std::printf("%s", AccuracyHeader().c_str());
    for (size_t i = 0; i < loaded.size(); ++i) {
      for (const AccuracyRow& row : MeasureRefinementAccuracy(loaded[i], options.accuracy_pairs)) {
        std::printf("%s\n", AccuracyRowText(options.indexes[i], row).c_str());
      }
    }
  }
  for (const QueryBenchTable* table : QueryBenchTables()) {
    if (some_only && !only(table->flag)) continue;
    std::printf("\n%s\n%s", table->title.c_str(), table->header().c_str());
    for (size_t i = 0; i < loaded.size(); ++i) table->run(options.indexes[i], loaded[i]);
  }
  if (!some_only || options.field_only) {
    std::printf("\nDistance fields (5 interior sources, one at a time)\n%s", FieldHeader().c_str());
    for (size_t i = 0; i < loaded.size(); ++i) {
      if (const absl::Status status = BenchField(options.indexes[i], loaded[i]); !status.ok()) {
        std::fprintf(stderr, "%s: %s\n", options.indexes[i].c_str(), status.ToString().c_str());
        return 1;
      }
    }
  }
  return 0;
}

}  // namespace geodex::bench
