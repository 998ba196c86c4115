#include "tests/accuracy/accuracy.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <random>
#include <span>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/geodesic/exact_geodesic.h"

namespace geodex::accuracy {

ErrorStats ErrorStats::Of(std::vector<double> errors) {
  ErrorStats s;
  s.count = static_cast<int64_t>(errors.size());
  if (errors.empty()) return s;
  double sum2 = 0, sum = 0;
  for (double& e : errors) {
    sum2 += e * e;
    e = std::abs(e);
    sum += e;
  }
  std::sort(errors.begin(), errors.end());
  s.rms = std::sqrt(sum2 / errors.size());
  s.mean = sum / errors.size();
  s.p99 = errors[std::min(errors.size() - 1, static_cast<size_t>(0.99 * errors.size()))];
  s.max = errors.back();
  return s;
}

std::string AccuracyReport::MarkdownHeader() {
  return "| case | pairs | RMS | mean | p99 | max | far p99 | near pairs | near RMS | near p99 | "
         "near p99 (path mode) | near max (path mode) | near p99 (exact mode) | "
         "RMS (path mode) | baseline RMS | path/exact p99 | traced path/exact p99 |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
}

std::string AccuracyReport::ToMarkdownRow(const std::string& label) const {
  auto pct = [](double x) { return absl::StrFormat("%.3f%%", 100 * x); };
  return absl::StrFormat(
      "| %s | %d | %s | %s | %s | %s | %s | %d | %s | %s | %s | %s | %s | %s | %s | %.4f | %.4f "
      "|\n",
      label, all.count, pct(all.rms), pct(all.mean), pct(all.p99), pct(all.max), pct(far.p99),
      near.count, pct(near.rms), pct(near.p99), pct(near_path_mode.p99), pct(near_path_mode.max),
      pct(near_exact_mode.p99), pct(all_path_mode.rms), pct(baseline.rms),
      path_ratio.count ? 1 + path_ratio.p99 : 0.0,
      traced_path_ratio.count ? 1 + traced_path_ratio.p99 : 0.0);
}

namespace {

// `count` area-uniform random points of `faces`.
std::vector<mesh::SurfacePoint> PointsOnFaces(const mesh::Mesh& mesh,
                                              std::span<const int32_t> faces, int32_t count,
                                              std::mt19937_64& rng) {
  std::vector<double> cumulative;
  double total = 0;
  for (int32_t f : faces) cumulative.push_back(total += mesh.Area(f));
  std::vector<mesh::SurfacePoint> points;
  if (faces.empty()) return points;
  std::uniform_real_distribution<double> u(0, 1);
  for (int32_t k = 0; k < count; ++k) {
    const size_t i =
        std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total) - cumulative.begin();
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;  // uniform on the triangle
    points.push_back({faces[std::min(i, faces.size() - 1)], {1 - a - b, a, b}});
  }
  return points;
}

// Draws area-uniform points of the faces lifted into a geodesic triangle or
// one of its neighbours.
class NearPointSampler {
 public:
  NearPointSampler(const mesh::Mesh& mesh, const query::QueryEngine& engine)
      : mesh_(mesh), engine_(engine), faces_of_(engine.index().num_triangles()) {
    for (int32_t f = 0; f < mesh.num_faces(); ++f) {
      const int32_t t = engine.Lift({f, {1.0 / 3, 1.0 / 3, 1.0 / 3}}).triangle;
      if (t >= 0) faces_of_[t].push_back(f);
    }
  }

  std::vector<mesh::SurfacePoint> Sample(const mesh::SurfacePoint& p, int32_t count,
                                         std::mt19937_64& rng) const {
    const int32_t t = engine_.Lift(p).triangle;
    std::vector<int32_t> faces = faces_of_[t];
    for (int32_t n : engine_.index().triangles()[t].neighbor) {
      if (n >= 0) faces.insert(faces.end(), faces_of_[n].begin(), faces_of_[n].end());
    }
    return PointsOnFaces(mesh_, faces, count, rng);
  }

 private:
  const mesh::Mesh& mesh_;
  const query::QueryEngine& engine_;
  std::vector<std::vector<int32_t>> faces_of_;
};

}  // namespace

std::vector<mesh::SurfacePoint> RandomSurfacePoints(const mesh::Mesh& mesh, int32_t count,
                                                    uint64_t seed) {
  std::vector<int32_t> faces(mesh.num_faces());
  std::iota(faces.begin(), faces.end(), 0);
  std::mt19937_64 rng(seed);
  return PointsOnFaces(mesh, faces, count, rng);
}

absl::StatusOr<Engines> MakeEngines(std::shared_ptr<const index::Index> index,
                                    query::QueryOptions base) {
  Engines engines;
  for (auto [mode, engine] : {std::pair{query::NearPairs::kUnfold, &engines.unfold},
                              std::pair{query::NearPairs::kPath, &engines.path},
                              std::pair{query::NearPairs::kExact, &engines.exact}}) {
    query::QueryOptions options = base;
    options.near_pairs = mode;
    auto made = query::QueryEngine::Create(index, options);
    if (!made.ok()) return made.status();
    *engine = *std::move(made);
  }
  return engines;
}

AccuracyReport MeasureAccuracy(const mesh::Mesh& mesh, const Engines& engines,
                               const AccuracyOptions& options) {
  const query::QueryEngine& engine = *engines.unfold;
  const auto points = RandomSurfacePoints(mesh, options.num_points, options.seed);
  const int32_t sources = std::min(options.num_sources, options.num_points);
  std::vector<double> all, far, near, near_path, all_path, near_exact, all_exact, baseline,
      path_ratio, traced_ratio;
  geodesic::ExactGeodesicSolver solver(mesh);
  query::QueryScratch scratch;
  const double tiny = 1e-9 * mesh.BoundingBoxDiagonal();
  int32_t paths_left = options.num_paths;
  const NearPointSampler near_sampler(mesh, engine);
  std::mt19937_64 near_rng(options.seed + 1);
  for (int32_t s = 0; s < sources; ++s) {
    if (!solver.Propagate({points[s]}).ok()) continue;
    for (const mesh::SurfacePoint& q :
         near_sampler.Sample(points[s], options.num_near_points, near_rng)) {
      const double exact = solver.DistanceAt(q);
      if (!(exact > tiny) || !std::isfinite(exact) || !engine.IsNearPair(points[s], q)) continue;
      near.push_back((*engine.Distance(points[s], q) - exact) / exact);
      near_path.push_back((*engines.path->Distance(points[s], q) - exact) / exact);
      near_exact.push_back((*engines.exact->Distance(points[s], q, &scratch) - exact) / exact);
    }
    for (int32_t k = sources; k < options.num_points; ++k) {
      const double exact = solver.DistanceAt(points[k]);
      if (!(exact > tiny) || !std::isfinite(exact)) continue;
      const double approx = *engine.Distance(points[s], points[k]);
      const double e = (approx - exact) / exact;
      all.push_back(e);
      const bool is_near = engine.IsNearPair(points[s], points[k]);
      (is_near ? near : far).push_back(e);
      baseline.push_back((engine.LinearInterpolationDistance(points[s], points[k]) - exact) /
                         exact);
      const double by_path = *engines.path->Distance(points[s], points[k]);
      all_path.push_back((by_path - exact) / exact);
      if (is_near) near_path.push_back((by_path - exact) / exact);
      const double fixed = *engines.exact->Distance(points[s], points[k], &scratch);
      all_exact.push_back((fixed - exact) / exact);
      if (is_near) near_exact.push_back((fixed - exact) / exact);
      if (paths_left > 0 && (k % 3 == 0)) {
        auto length = [](const std::vector<query::PathPoint>& path) {
          double sum = 0;
          for (size_t i = 1; i < path.size(); ++i) {
            sum += (path[i].position - path[i - 1].position).norm();
          }
          return sum;
        };
        auto path = engine.Path(points[s], points[k]);
        auto traced = engine.TracePath(points[s], points[k]);
        if (path.ok() && traced.ok()) {
          path_ratio.push_back(length(*path) / exact - 1);
          traced_ratio.push_back(length(*traced) / exact - 1);
          --paths_left;
        }
      }
    }
  }
  AccuracyReport report;
  report.all = ErrorStats::Of(all);
  report.far = ErrorStats::Of(far);
  report.near = ErrorStats::Of(near);
  report.near_path_mode = ErrorStats::Of(near_path);
  report.all_path_mode = ErrorStats::Of(all_path);
  report.near_exact_mode = ErrorStats::Of(near_exact);
  report.all_exact_mode = ErrorStats::Of(all_exact);
  report.baseline = ErrorStats::Of(baseline);
  // Path ratio: keep the signed excess so p99 reads as ratio - 1.
  ErrorStats paths = ErrorStats::Of(path_ratio);
  report.path_ratio = paths;
  report.traced_path_ratio = ErrorStats::Of(traced_ratio);
  return report;
}

}  // namespace geodex::accuracy
