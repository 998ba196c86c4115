// geodex-accuracy: the full accuracy run, by distance scale.
//
//   geodex-accuracy MESH... --samples 250,500,1000,2000 [--sources S] [--points N]
//                   [--per-bin N] [--index-dir DIR] [--threads T] [--modes unfold,default,...]
//
// For each mesh and each m: builds the index (or reuses DIR/<mesh>-m<M>.gdx),
// draws pairs at every distance scale with their exact distances (see
// accuracy.h), and prints per bin and point kind the error of each answer
// mode, then a summary row with the worst bin. MESH may be builtin:NAME.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "CLI/CLI.hpp"
#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/builder/mesh_arrays.h"
#include "core/common/status_macros.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"
#include "core/query/input_queries.h"
#include "core/query/internal/query_knobs.h"
#include "core/validation/calibration.h"
#include "core/validation/error_map.h"
#include "tests/accuracy/accuracy.h"

namespace geodex {
namespace {

absl::StatusOr<mesh::Mesh> LoadInput(const std::string& path) {
  if (path == "builtin:sphere") return mesh::gen::Sphere(5, 1.0);
  if (path == "builtin:torus") return mesh::gen::Torus(96, 48, 2.0, 0.7);
  if (path == "builtin:folded") return mesh::gen::FoldedSheet(40, 24, 2.0, 1.0, 1.1);
  if (path == "builtin:cylinder") return mesh::gen::Cylinder(64, 24, 1.0, 3.0);
  return mesh::LoadMesh(path);
}

struct Flags {
  std::vector<std::string> meshes;
  std::vector<int32_t> samples = {1000};
  validation::PairOptions pairs;
  std::string index_dir;
  int threads = 0;
  std::vector<std::string> modes = {"unfold", "default", "bounds", "tol0.005"};
  int32_t path_sources = 0, path_points = 0;
  bool no_refinement = false;
  bool error_driven = false;
};

// The index of `m` for `count` samples: DIR/<name>-m<count><suffix>.gdx when
// it exists, else built (with `spacing_weight` when not empty) and cached
// there; calibrated in memory when it has no calibration, as the builder
// would (its own seed, on the mesh it sampled), so that bounds can be
// measured.
absl::StatusOr<std::shared_ptr<const index::Index>> IndexFor(
    const Flags& flags, const mesh::Mesh& m, const std::string& name, int32_t count,
    const std::string& suffix, const std::vector<double>& spacing_weight) {
  const std::string file =
      absl::StrFormat("%s/%s-m%d%s%s.gdx", flags.index_dir.empty() ? "/tmp" : flags.index_dir, name,
                      count, flags.no_refinement ? "-noref" : "", suffix);
  if (flags.index_dir.empty() || !std::filesystem::exists(file)) {
    builder::BuildOptions build_options;
    build_options.num_samples = count;
    build_options.threads = flags.threads;
    build_options.spacing_weight = spacing_weight;
    GEODEX_ASSIGN_OR_RETURN(const builder::PreparedMesh prepared,
                            builder::PrepareMesh(m, {}, count, !flags.no_refinement));
    builder::BuildSummary summary;
    GEODEX_ASSIGN_OR_RETURN(const auto data,
                            builder::BuildPreparedIndex(prepared, build_options, &summary));
    GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, file));
    std::fprintf(stderr, "built %s: %s%s", file.c_str(), prepared.record.report.c_str(),
                 summary.ToText().c_str());
  }
  GEODEX_ASSIGN_OR_RETURN(std::shared_ptr<const index::Index> index, index::Index::Open(file));
  if (index->accuracy() == nullptr) {
    GEODEX_ASSIGN_OR_RETURN(
        const builder::PreparedMesh prepared,
        builder::PrepareMesh(m, {}, static_cast<int32_t>(index->header().params.requested_samples),
                             index->split_vertices() > 0));
    GEODEX_ASSIGN_OR_RETURN(const validation::Calibration calibration,
                            validation::Calibrate(prepared.mesh, index));
    std::fprintf(stderr, "calibrated %s in memory\n", file.c_str());
    index::IndexData data = index::ToIndexData(*index);
    data.accuracy = {calibration.record};
    data.spread_bounds = {calibration.spread};
    GEODEX_ASSIGN_OR_RETURN(std::string bytes, index::SerializeIndex(data));
    GEODEX_ASSIGN_OR_RETURN(index, index::Index::FromBytes(std::move(bytes)));
  }
  return index;
}

// Error-driven placement at the same m: the spacing weights of the error
// map of `fps`, the farthest-point index (core/validation/error_map.h).
absl::StatusOr<std::vector<double>> PlacementWeights(const Flags& flags, const mesh::Mesh& m,
                                                     std::shared_ptr<const index::Index> fps,
                                                     int32_t count) {
  GEODEX_ASSIGN_OR_RETURN(const builder::PreparedMesh prepared,
                          builder::PrepareMesh(m, {}, count, !flags.no_refinement));
  validation::ErrorMapOptions map_options;
  map_options.threads = flags.threads;
  GEODEX_ASSIGN_OR_RETURN(const std::vector<double> map,
                          validation::VertexErrorMap(prepared.mesh, std::move(fps), map_options));
  return validation::SpacingWeights(prepared.mesh, map);
}

absl::Status Measure(const Flags& flags, const std::string& label,
                     const std::vector<validation::ExactPair>& pairs,
                     std::shared_ptr<const index::Index> index) {
  GEODEX_ASSIGN_OR_RETURN(auto walking, query::QueryEngine::Create(index));
  GEODEX_ASSIGN_OR_RETURN(auto tracing,
                          query::CreateQueryEngine(index, {}, {.walk_near_pairs = false}));
  for (const std::string& mode : flags.modes) {
    query::DistanceOptions options;
    bool bounds = false;
    const auto& engine = mode == "nowalk" ? tracing : walking;
    if (mode == "unfold") {
      options.near_pairs = query::NearPairs::kUnfold;
    } else if (mode == "exact") {
      options.near_pairs = query::NearPairs::kExact;
    } else if (mode == "bounds") {
      bounds = true;
    } else if (mode.rfind("tol", 0) == 0) {
      options.tolerance = std::stod(mode.substr(3));
      bounds = true;
    } else if (mode != "default" && mode != "trace" && mode != "nowalk") {
      return absl::InvalidArgumentError("unknown mode " + mode);
    }
    query::QueryScratch scratch;
    int64_t failed = 0;
    // The pairs are in the file's ids, as a caller's are.
    GEODEX_ASSIGN_OR_RETURN(const auto queries, query::InputQueries::Create(engine));
    query::EnginePoints p, q;
    accuracy::AnswerFn answer = [&](const mesh::SurfacePoint& input_p,
                                    const mesh::SurfacePoint& input_q) {
      accuracy::Answer a;
      absl::StatusOr<double> d = absl::InternalError("no internal point");
      if (queries->Read({&input_p, 1}, nullptr, &p).ok() &&
          queries->Read({&input_q, 1}, nullptr, &q).ok()) {
        d = mode == "trace"
                ? queries->TracedDistance(p, 0, q, 0)
                : queries->Distance(p, 0, q, 0, options, &scratch, bounds ? &a.bound : nullptr);
      }
      if (!d.ok()) ++failed;
      a.distance = d.value_or(std::numeric_limits<double>::quiet_NaN());
      return a;
    };
    const auto start = std::chrono::steady_clock::now();
    const accuracy::ModeReport report = accuracy::Evaluate(pairs, answer);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "%s %s: %.2f us per pair, %lld failed\n", label.c_str(), mode.c_str(),
                 1e6 * seconds / pairs.size(), static_cast<long long>(failed));
    std::printf("%s", accuracy::MarkdownRows(
                          absl::StrFormat("%s m=%d %s", label, index->num_samples(), mode), report)
                          .c_str());
    std::fflush(stdout);
  }
  return absl::OkStatus();
}

absl::Status Run(const Flags& flags) {
  std::printf("%s", accuracy::MarkdownHeader().c_str());
  for (const std::string& path : flags.meshes) {
    GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh m, LoadInput(path));
    const std::string name = std::filesystem::path(path).stem().string();
    for (int32_t count : flags.samples) {
      GEODEX_ASSIGN_OR_RETURN(auto index, IndexFor(flags, m, name, count, "", {}));
      validation::PairOptions pair_options = flags.pairs;
      pair_options.threads = flags.threads;
      const auto pairs = validation::DrawPairs(m, index->num_samples(), pair_options);
      GEODEX_RETURN_IF_ERROR(Measure(flags, name, pairs, index));
      if (flags.error_driven) {
        GEODEX_ASSIGN_OR_RETURN(const std::vector<double> weights,
                                PlacementWeights(flags, m, index, count));
        GEODEX_ASSIGN_OR_RETURN(auto placed, IndexFor(flags, m, name, count, "-placed", weights));
        // The same pairs: L differs by the few samples repair adds, so a
        // handful of pairs may sit in a neighbouring bin.
        GEODEX_RETURN_IF_ERROR(Measure(flags, name + " error-driven", pairs, placed));
      }
    }
  }
  return absl::OkStatus();
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app{"geodex-accuracy: query accuracy against exact geodesics, by distance scale."};
  geodex::Flags flags;
  app.add_option("meshes", flags.meshes, "Mesh files or builtin:NAME")->required();
  app.add_option("--samples", flags.samples, "Values of m")->delimiter(',');
  app.add_option("--sources", flags.pairs.num_sources,
                 "Exact propagations, half from vertices, half from points inside faces");
  app.add_option("--points", flags.pairs.uniform_points, "Area-uniform targets per source");
  app.add_option("--per-bin", flags.pairs.per_bin_points,
                 "Targets per source drawn in each distance bin");
  app.add_option("--seed", flags.pairs.seed, "Random seed");
  app.add_option("--index-dir", flags.index_dir, "Cache built indexes here");
  app.add_flag("--no-refinement", flags.no_refinement,
               "Build without splitting long edges (geodex-build --no-refinement)");
  app.add_flag("--error-driven", flags.error_driven,
               "Also build each m with error-driven placement (spacing weights from the "
               "farthest-point index's error map) and measure it on the same pairs");
  app.add_option("--threads", flags.threads, "Builder and exact-propagation threads (0: all)");
  app.add_option(
         "--modes", flags.modes,
         "Answer modes: unfold (pure O(1)), default, exact (near pairs exactly), bounds "
         "(default with error bounds), tolX (tolerance X, e.g. tol0.005), trace, nowalk (default "
         "without the walks of near pairs: the trace only)")
      ->delimiter(',');
  CLI11_PARSE(app, argc, argv);
  const absl::Status status = geodex::Run(flags);
  if (!status.ok()) {
    std::fprintf(stderr, "geodex-accuracy: %s\n", status.ToString().c_str());
    return 1;
  }
  return 0;
}
