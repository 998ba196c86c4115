// matrix_codes: what the 24-bit sample distance codes (index/sample_matrix.h)
// cost in accuracy. For each mesh and m, one build, written twice: with the
// float32 matrix and with the codes. Prints the codes' relative error on the
// matrix entries (p50, p99, largest), and how far the two indexes' O(1)
// answers and default answers lie apart on area-uniform pairs (relative
// RMS, p99, largest), beside the O(1) answer's own error scale (its
// relative RMS against the float32 index's default answer, which is exact
// or walked below kRefineScale L, for each index).
//
// With --round-bits K, the second index is the float32 one with every entry
// rounded to K mantissa bits in memory instead: what a code of another
// width would cost, without writing it.
//
//   matrix_codes MESH... [--samples 1000,3000] [--pairs 20000] [--threads 2]
//                [--round-bits K]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/common/status_macros.h"
#include "core/index/index.h"
#include "core/mesh/mesh_repair.h"
#include "core/query/engine/query_engine.h"
#include "core/validation/pair_sampling.h"

namespace geodex {
namespace {

struct Spread {
  double rms = 0, p50 = 0, p99 = 0, largest = 0;
};

Spread SpreadOf(std::vector<double> e) {
  Spread s;
  if (e.empty()) return s;
  double sum = 0;
  for (double x : e) sum += x * x;
  s.rms = std::sqrt(sum / e.size());
  std::sort(e.begin(), e.end());
  s.p50 = e[e.size() / 2];
  s.p99 = e[std::min(e.size() - 1, static_cast<size_t>(0.99 * e.size()))];
  s.largest = e.back();
  return s;
}

absl::StatusOr<std::shared_ptr<const query::QueryEngine>> EngineOf(index::IndexData& data,
                                                                   index::MatrixLayout layout) {
  data.sample_matrix = layout;
  GEODEX_ASSIGN_OR_RETURN(std::string bytes, index::SerializeIndex(data));
  GEODEX_ASSIGN_OR_RETURN(auto index, index::Index::FromBytes(std::move(bytes)));
  return query::QueryEngine::Create(std::move(index));
}

int Run(const std::string& path, int32_t samples, int32_t num_pairs, int threads, int round_bits) {
  absl::StatusOr<mesh::RepairedMesh> repaired = mesh::LoadAndRepairMesh(path);
  if (!repaired.ok()) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), std::string(repaired.status().message()).c_str());
    return 1;
  }
  absl::StatusOr<builder::PreparedMesh> prepared =
      builder::PrepareMesh(repaired->mesh, {}, samples, /*refine=*/true);
  if (!prepared.ok()) return 1;
  builder::BuildOptions options;
  options.num_samples = samples;
  options.threads = threads;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data = builder::BuildIndex(prepared->mesh, options, &summary);
  if (!data.ok()) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), std::string(data.status().message()).c_str());
    return 1;
  }
  absl::StatusOr<std::shared_ptr<const query::QueryEngine>> full =
      EngineOf(*data, index::MatrixLayout::kFull);
  absl::StatusOr<std::shared_ptr<const query::QueryEngine>> coded;
  if (round_bits > 0) {
    index::IndexData rounded = *data;
    for (float& x : rounded.sample_distances) {
      if (!std::isfinite(x) || x == 0) continue;
      int e;
      const double f = std::frexp(static_cast<double>(x), &e);
      const double q = std::ldexp(1.0, round_bits + 1);
      x = static_cast<float>(std::ldexp(std::nearbyint(f * q) / q, e));
    }
    coded = EngineOf(rounded, index::MatrixLayout::kFull);
  } else {
    coded = EngineOf(*data, index::MatrixLayout::kCoded);
  }
  if (!full.ok() || !coded.ok()) return 1;

  // The matrix entries.
  std::vector<double> entries;
  const index::SampleMatrix& a = (*full)->index().matrix();
  const index::SampleMatrix& b = (*coded)->index().matrix();
  const int32_t m = a.num_samples();
  for (int32_t i = 1; i < m; ++i) {
    for (int32_t j = 0; j < i; ++j) {
      if (a(i, j) > 0 && std::isfinite(a(i, j))) {
        entries.push_back(std::abs(b(i, j) - a(i, j)) / a(i, j));
      }
    }
  }
  // Area-uniform pairs.
  const mesh::Mesh& mesh = prepared->mesh;
  const std::vector<mesh::SurfacePoint> p = validation::RandomSurfacePoints(mesh, num_pairs, 11);
  const std::vector<mesh::SurfacePoint> q = validation::RandomSurfacePoints(mesh, num_pairs, 12);
  std::vector<double> o1, answers, o1_error, coded_error;
  for (int32_t k = 0; k < num_pairs; ++k) {
    const double fa = (*full)->O1Distance(p[k], q[k]), ca = (*coded)->O1Distance(p[k], q[k]);
    const absl::StatusOr<double> fd = (*full)->Distance(p[k], q[k]);
    const absl::StatusOr<double> cd = (*coded)->Distance(p[k], q[k]);
    if (!fd.ok() || !cd.ok() || !(*fd > 0) || !std::isfinite(*fd)) continue;
    o1.push_back(std::abs(ca - fa) / *fd);
    answers.push_back(std::abs(*cd - *fd) / *fd);
    o1_error.push_back(std::abs(fa - *fd) / *fd);
    coded_error.push_back(std::abs(ca - *fd) / *fd);
  }
  const Spread e = SpreadOf(entries), s = SpreadOf(o1), d = SpreadOf(answers),
               own = SpreadOf(o1_error), coded_own = SpreadOf(coded_error);
  std::printf(
      "%-22s m=%5d | entries p50 %.2e p99 %.2e max %.2e | O(1) apart rms %.2e p99 %.2e max "
      "%.2e | default apart rms %.2e p99 %.2e max %.2e | O(1) error rms, float32 %.2e, codes "
      "%.2e (%zu pairs)\n",
      path.substr(path.find_last_of('/') + 1).c_str(), m, e.p50, e.p99, e.largest, s.rms, s.p99,
      s.largest, d.rms, d.p99, d.largest, own.rms, coded_own.rms, answers.size());
  std::fflush(stdout);
  return 0;
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app{"The 24-bit sample distance codes against the float32 matrix"};
  std::vector<std::string> meshes;
  std::vector<int32_t> samples = {1000};
  int32_t pairs = 20000;
  int threads = 2;
  int round_bits = 0;
  app.add_option("meshes", meshes, "meshes (.obj, .ply, .off, .stl, .glb)")->required();
  app.add_option("--samples", samples, "m of each build")->delimiter(',');
  app.add_option("--pairs", pairs, "area-uniform pairs");
  app.add_option("--threads", threads, "builder threads");
  app.add_option("--round-bits", round_bits, "instead of the codes, float32 rounded to this many mantissa bits");
  CLI11_PARSE(app, argc, argv);
  int status = 0;
  for (const std::string& path : meshes) {
    for (int32_t m : samples) status |= geodex::Run(path, m, pairs, threads, round_bits);
  }
  return status;
}
