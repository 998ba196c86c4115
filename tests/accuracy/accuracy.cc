#include "tests/accuracy/accuracy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <span>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/geodesic/exact_geodesic.h"

namespace geodex::accuracy {
namespace {

// The default target's far band starts here (core/validation/target_error.h).
constexpr double kFarL1000 = 8;

std::string Pct(double x) { return absl::StrFormat("%.3f%%", 100 * x); }

// One Markdown row of MarkdownHeader's columns.
std::string Row(const std::string& label, const char* kind, const std::string& bin,
                const BinReport& r) {
  return absl::StrFormat(
      "| %s | %s | %s | %d | %s | %s | %s | %s | %s |\n", label, kind, bin, r.error.count,
      Pct(r.error.rms), Pct(r.error.p99), Pct(r.error.max),
      std::isnan(r.coverage) ? "-" : Pct(r.coverage),
      std::isnan(r.median_bound) ? "-" : absl::StrFormat("%.2f", r.median_bound / r.p90_abs_error));
}

double Percentile(std::vector<double> x, double q) {
  if (x.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(x.begin(), x.end());
  return x[std::min(x.size() - 1, static_cast<size_t>(q * x.size()))];
}

}  // namespace

const char* BinName(int bin) { return validation::ScaleBinName(bin); }

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

ModeReport Evaluate(const std::vector<ExactPair>& pairs, const AnswerFn& answer, double unit) {
  struct Acc {
    std::vector<double> rel, abs, bound;
    int64_t covered = 0;
  };
  std::array<Acc, kNumBins> vertex, interior, all;
  std::array<Acc, kNumFixedBins> fixed_vertex, fixed_interior;
  Acc far_vertex, far_interior;
  std::vector<double> uniform;
  for (const ExactPair& pair : pairs) {
    const Answer a = answer(pair.p, pair.q);
    const double rel = (a.distance - pair.exact) / pair.exact;
    const double abs = std::abs(a.distance - pair.exact);
    std::vector<Acc*> accs = {&(pair.vertices ? vertex : interior)[pair.bin], &all[pair.bin]};
    if (unit > 0) {
      const int fixed = validation::FixedBinOf(pair.exact, unit);
      accs.push_back(&(pair.vertices ? fixed_vertex : fixed_interior)[fixed]);
      if (pair.exact >= kFarL1000 * unit) accs.push_back(pair.vertices ? &far_vertex : &far_interior);
    }
    for (Acc* acc : accs) {
      acc->rel.push_back(rel);
      acc->abs.push_back(abs);
      if (!std::isnan(a.bound)) {
        acc->bound.push_back(a.bound);
        // Exact answers carry a bound of 0: allow the rounding of two exact
        // propagations (from either end) that agree to about 1e-12.
        if (abs <= a.bound + 1e-9 * pair.exact) ++acc->covered;
      }
    }
    if (pair.uniform && !pair.vertices) uniform.push_back(rel);
  }
  auto finish = [](const Acc& acc) {
    BinReport r;
    r.error = ErrorStats::Of(acc.rel);
    if (!acc.bound.empty()) {
      r.coverage = static_cast<double>(acc.covered) / acc.bound.size();
      r.median_bound = Percentile(acc.bound, 0.5);
      r.p90_abs_error = Percentile(acc.abs, 0.9);
    }
    return r;
  };
  ModeReport report;
  for (int b = 0; b < kNumBins; ++b) {
    report.vertex[b] = finish(vertex[b]);
    report.interior[b] = finish(interior[b]);
    report.all[b] = finish(all[b]);
    for (const BinReport* r : {&report.vertex[b], &report.interior[b]}) {
      if (r->error.p99 > report.worst_p99) {
        report.worst_p99 = r->error.p99;
        report.worst_bin = b;
      }
    }
  }
  for (int b = 0; b < kNumFixedBins; ++b) {
    report.fixed_vertex[b] = finish(fixed_vertex[b]);
    report.fixed_interior[b] = finish(fixed_interior[b]);
  }
  report.far_vertex = finish(far_vertex);
  report.far_interior = finish(far_interior);
  report.uniform = ErrorStats::Of(uniform);
  return report;
}

std::string MarkdownHeader() {
  return "| case | points | bin | pairs | RMS | p99 | max | coverage | median bound / p90 error |\n"
         "|---|---|---|---|---|---|---|---|---|\n";
}

std::string MarkdownRows(const std::string& label, const ModeReport& report) {
  std::string out;
  for (int kind = 0; kind < 2; ++kind) {
    for (int b = 0; b < kNumBins; ++b) {
      const BinReport& r = (kind == 0 ? report.vertex : report.interior)[b];
      if (r.error.count > 0) out += Row(label, kind == 0 ? "vertex" : "interior", BinName(b), r);
    }
  }
  // The area-uniform pairs alone, every scale: the figure a target error
  // (geodex-build --target-error) is stated in.
  if (report.uniform.count > 0) {
    out += absl::StrFormat("| %s | uniform | all | %d | %s | %s | %s | - | - |\n", label,
                           report.uniform.count, Pct(report.uniform.rms), Pct(report.uniform.p99),
                           Pct(report.uniform.max));
  }
  out += absl::StrFormat("| %s | **worst** | %s | | | **%s** | | | |\n", label,
                         BinName(report.worst_bin), Pct(report.worst_p99));
  return out;
}

std::string MarkdownFixedRows(const std::string& label, const ModeReport& report, double target) {
  std::string out;
  for (int kind = 0; kind < 2; ++kind) {
    for (int b = 0; b < kNumFixedBins; ++b) {
      const BinReport& r = (kind == 0 ? report.fixed_vertex : report.fixed_interior)[b];
      if (r.error.count == 0) continue;
      out += Row(label, kind == 0 ? "vertex" : "interior",
                 absl::StrCat(validation::FixedBinName(b), " L1000"), r);
    }
  }
  const bool rms_met = report.uniform.rms <= target;
  const bool vertex_met = report.far_vertex.error.p99 <= 4 * target;
  const bool interior_met = report.far_interior.error.p99 <= 4 * target;
  out += absl::StrFormat(
      "| %s | **target %s** | uniform RMS %s (<= %s)%s; >=8 L1000 p99 vertex %s%s, interior "
      "%s%s (<= %s) | %d / %d / %d | | | | | |\n",
      label, rms_met && vertex_met && interior_met ? "met" : "NOT met", Pct(report.uniform.rms),
      Pct(target), rms_met ? "" : " NOT met", Pct(report.far_vertex.error.p99),
      vertex_met ? "" : " NOT met", Pct(report.far_interior.error.p99),
      interior_met ? "" : " NOT met", Pct(4 * target), report.uniform.count,
      report.far_vertex.error.count, report.far_interior.error.count);
  return out;
}

PathReport MeasurePaths(const mesh::Mesh& mesh, const query::QueryEngine& engine,
                        int32_t num_sources, int32_t num_points, uint64_t seed) {
  const auto points = validation::RandomSurfacePoints(mesh, num_sources + num_points, seed);
  geodesic::ExactGeodesicSolver solver(mesh);
  const double tiny = 1e-9 * mesh.BoundingBoxDiagonal();
  auto length = [](const std::vector<query::PathPoint>& path) {
    double sum = 0;
    for (size_t i = 1; i < path.size(); ++i)
      sum += (path[i].position - path[i - 1].position).norm();
    return sum;
  };
  std::vector<double> path_ratio, traced_ratio;
  for (int32_t s = 0; s < num_sources; ++s) {
    if (!solver.Propagate({points[s]}).ok()) continue;
    for (int32_t k = num_sources; k < num_sources + num_points; ++k) {
      const double exact = solver.DistanceAt(points[k]);
      if (!(exact > tiny) || !std::isfinite(exact)) continue;
      auto path = engine.Path(points[s], points[k]);
      auto traced = engine.TracePath(points[s], points[k]);
      if (path.ok() && traced.ok()) {
        path_ratio.push_back(length(*path) / exact - 1);
        traced_ratio.push_back(length(*traced) / exact - 1);
      }
    }
  }
  return {ErrorStats::Of(path_ratio), ErrorStats::Of(traced_ratio)};
}

}  // namespace geodex::accuracy
