#include "tests/accuracy/accuracy_harness.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/common/status_macros.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"
#include "core/query/input_queries.h"
#include "core/query/engine/query_knobs.h"
#include "core/validation/calibration.h"
#include "core/validation/error_map.h"
#include "tests/accuracy/accuracy.h"

namespace geodex::accuracy {
namespace {

// Error-driven placement at the same m: the spacing weights of the error
// map of `fps`, the farthest-point index (core/validation/error_map.h).
absl::StatusOr<std::vector<double>> PlacementWeights(const HarnessFlags& flags, const mesh::Mesh& m,
                                                     std::shared_ptr<const index::Index> fps,
                                                     int32_t count) {
  GEODEX_ASSIGN_OR_RETURN(const builder::PreparedMesh prepared,
                          builder::PrepareMesh(m, {}, count, !flags.no_split));
  validation::ErrorMapOptions map_options;
  map_options.threads = flags.threads;
  GEODEX_ASSIGN_OR_RETURN(const std::vector<double> map,
                          validation::VertexErrorMap(prepared.mesh, std::move(fps), map_options));
  return validation::SpacingWeights(prepared.mesh, map);
}

// Builds the index of `m` with `count` samples into `file` (not calibrated).
absl::Status BuildIndexFile(const HarnessFlags& flags, const mesh::Mesh& m, int32_t count,
                            const std::vector<double>& spacing_weight, const std::string& file) {
  builder::BuildOptions build_options;
  build_options.num_samples = count;
  build_options.threads = flags.threads;
  build_options.spacing_weight = spacing_weight;
  GEODEX_ASSIGN_OR_RETURN(const builder::PreparedMesh prepared,
                          builder::PrepareMesh(m, {}, count, !flags.no_split));
  builder::BuildSummary summary;
  GEODEX_ASSIGN_OR_RETURN(const auto data,
                          builder::BuildPreparedIndex(prepared, build_options, &summary));
  GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, file));
  std::fprintf(stderr, "built %s: %s%s", file.c_str(), prepared.record.report.c_str(),
               summary.ToText().c_str());
  return absl::OkStatus();
}

// `index` of `m` with its calibration added in memory.
absl::StatusOr<std::shared_ptr<const index::Index>> CalibratedInMemory(
    const mesh::Mesh& m, std::shared_ptr<const index::Index> index, const std::string& file) {
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
  return index::Index::FromBytes(std::move(bytes));
}

// Measures one mode (ParseAnswerMode's) of `pairs` with `walking` or, for
// nowalk, `tracing`; prints its rows and timing.
absl::Status MeasureMode(const HarnessFlags& flags, const std::string& label,
                         const std::string& mode_name, const AnswerMode& mode,
                         const std::vector<validation::ExactPair>& pairs,
                         std::shared_ptr<const query::QueryEngine> engine, int32_t num_samples,
                         double unit) {
  query::QueryScratch scratch;
  int64_t failed = 0;
  // The pairs are in the file's ids, as a caller's are.
  GEODEX_ASSIGN_OR_RETURN(const auto queries, query::InputQueries::Create(engine));
  query::EnginePoints p, q;
  AnswerFn answer = [&](const mesh::SurfacePoint& input_p, const mesh::SurfacePoint& input_q) {
    Answer a;
    absl::StatusOr<double> d = absl::InternalError("no internal point");
    if (queries->Read({&input_p, 1}, nullptr, &p).ok() &&
        queries->Read({&input_q, 1}, nullptr, &q).ok()) {
      d = mode.trace ? queries->TracedDistance(p, 0, q, 0)
                     : queries->Distance(p, 0, q, 0, mode.options, &scratch,
                                         mode.bounds ? &a.bound : nullptr);
    }
    if (!d.ok()) ++failed;
    a.distance = d.value_or(std::numeric_limits<double>::quiet_NaN());
    return a;
  };
  const auto start = std::chrono::steady_clock::now();
  const ModeReport report = Evaluate(pairs, answer, unit);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::fprintf(stderr, "%s %s: %.2f us per pair, %lld failed\n", label.c_str(), mode_name.c_str(),
               1e6 * seconds / pairs.size(), static_cast<long long>(failed));
  const std::string row_label = absl::StrFormat("%s m=%d %s", label, num_samples, mode_name);
  std::printf("%s", MarkdownRows(row_label, report).c_str());
  if (flags.target_error > 0) {
    std::printf("%s", MarkdownFixedRows(row_label, report, flags.target_error).c_str());
  }
  std::fflush(stdout);
  return absl::OkStatus();
}

}  // namespace

AccuracyCommandLine::AccuracyCommandLine()
    : app_("geodex-accuracy: query accuracy against exact geodesics, by distance scale.") {
  HarnessFlags& f = flags_;
  app_.add_option("meshes", f.meshes, "Mesh files or builtin:NAME")->required();
  app_.add_option("--samples", f.samples, "Values of m")->delimiter(',');
  app_.add_option("--sources", f.pairs.num_sources,
                  "Exact propagations, half from vertices, half from points inside faces");
  app_.add_option("--points", f.pairs.uniform_points, "Area-uniform targets per source");
  app_.add_option("--per-bin", f.pairs.per_bin_points,
                  "Targets per source drawn in each distance bin");
  app_.add_option("--seed", f.pairs.seed, "Random seed");
  app_.add_option("--index-dir", f.index_dir, "Cache built indexes here");
  app_.add_flag("--no-split", f.no_split,
                "Build without splitting long edges (geodex-build --no-split)");
  app_.add_flag("--no-refinement", f.no_split)->group("");  // --no-split's old name
  app_.add_flag("--error-driven", f.error_driven,
                "Also build each m with error-driven placement (spacing weights from the "
                "farthest-point index's error map) and measure it on the same pairs");
  app_.add_option("--index", f.index_file,
                  "Measure this index file of the one mesh given (e.g. a default build) instead "
                  "of building one per --samples");
  app_.add_option("--target-error", f.target_error,
                  "Also print rows by fixed L1000 bin and the default target's checks for this "
                  "target error (0.005: the default build's)");
  app_.add_option("--threads", f.threads, "Builder and exact-propagation threads (0: all)");
  app_.add_option(
          "--modes", f.modes,
          "Answer modes: unfold (pure O(1)), default, exact (near pairs exactly), bounds "
          "(default with error bounds), tolX (tolerance X, e.g. tol0.005), belowX (default, "
          "refining every pair closer than X L1000, e.g. below8), trace, nowalk (default "
          "without the walks of near pairs: the trace only)")
      ->delimiter(',');
}

absl::StatusOr<mesh::Mesh> LoadHarnessMesh(const std::string& path) {
  if (path == "builtin:sphere") return mesh::gen::Sphere(5, 1.0);
  if (path == "builtin:torus") return mesh::gen::Torus(96, 48, 2.0, 0.7);
  if (path == "builtin:folded") return mesh::gen::FoldedSheet(40, 24, 2.0, 1.0, 1.1);
  if (path == "builtin:cylinder") return mesh::gen::Cylinder(64, 24, 1.0, 3.0);
  return mesh::LoadMesh(path);
}

absl::StatusOr<AnswerMode> ParseAnswerMode(const std::string& mode) {
  AnswerMode m;
  m.trace = mode == "trace";
  m.nowalk = mode == "nowalk";
  if (mode == "unfold") {
    m.options.near_pairs = query::NearPairs::kUnfold;
  } else if (mode == "exact") {
    m.options.near_pairs = query::NearPairs::kExact;
  } else if (mode == "bounds") {
    m.bounds = true;
  } else if (mode.rfind("below", 0) == 0) {
    m.options.refine_below_l1000 = std::stod(mode.substr(5));
    m.bounds = true;  // the bounds of the raised band's walks, measured too
  } else if (mode.rfind("tol", 0) == 0) {
    m.options.tolerance = std::stod(mode.substr(3));
    m.bounds = true;
  } else if (mode != "default" && !m.trace && !m.nowalk) {
    return absl::InvalidArgumentError("unknown mode " + mode);
  }
  return m;
}

std::string CachedIndexPath(const HarnessFlags& flags, const std::string& name, int32_t count,
                            const std::string& suffix) {
  return absl::StrFormat("%s/%s-m%d%s%s.gdx", flags.index_dir.empty() ? "/tmp" : flags.index_dir,
                         name, count, flags.no_split ? "-noref" : "", suffix);
}

absl::StatusOr<std::shared_ptr<const index::Index>> IndexFor(
    const HarnessFlags& flags, const mesh::Mesh& m, const std::string& name, int32_t count,
    const std::string& suffix, const std::vector<double>& spacing_weight) {
  const std::string file = CachedIndexPath(flags, name, count, suffix);
  if (flags.index_dir.empty() || !std::filesystem::exists(file)) {
    GEODEX_RETURN_IF_ERROR(BuildIndexFile(flags, m, count, spacing_weight, file));
  }
  GEODEX_ASSIGN_OR_RETURN(std::shared_ptr<const index::Index> index, index::Index::Open(file));
  if (index->accuracy() != nullptr) return index;
  return CalibratedInMemory(m, std::move(index), file);
}

absl::Status MeasureModes(const HarnessFlags& flags, const std::string& label,
                          const std::vector<validation::ExactPair>& pairs,
                          std::shared_ptr<const index::Index> index, double unit) {
  GEODEX_ASSIGN_OR_RETURN(auto walking, query::QueryEngine::Create(index));
  GEODEX_ASSIGN_OR_RETURN(auto tracing,
                          query::CreateQueryEngine(index, {}, {.walk_near_pairs = false}));
  for (const std::string& name : flags.modes) {
    GEODEX_ASSIGN_OR_RETURN(const AnswerMode mode, ParseAnswerMode(name));
    GEODEX_RETURN_IF_ERROR(MeasureMode(flags, label, name, mode, pairs,
                                       mode.nowalk ? tracing : walking, index->num_samples(), unit));
  }
  return absl::OkStatus();
}

absl::Status RunHarness(const HarnessFlags& flags) {
  if (!flags.index_file.empty() && flags.meshes.size() != 1) {
    return absl::InvalidArgumentError("--index measures the index of one mesh; give that mesh only");
  }
  std::printf("%s", MarkdownHeader().c_str());
  for (const std::string& path : flags.meshes) {
    GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh m, LoadHarnessMesh(path));
    const std::string name = std::filesystem::path(path).stem().string();
    const double unit = validation::ScaleLength(m.TotalArea(), validation::kFixedUnitSamples);
    validation::PairOptions pair_options = flags.pairs;
    pair_options.threads = flags.threads;
    if (!flags.index_file.empty()) {
      GEODEX_ASSIGN_OR_RETURN(std::shared_ptr<const index::Index> index,
                              index::Index::Open(flags.index_file));
      if (index->accuracy() == nullptr) {
        GEODEX_ASSIGN_OR_RETURN(index, CalibratedInMemory(m, std::move(index), flags.index_file));
      }
      const auto pairs = validation::DrawPairs(m, index->num_samples(), pair_options);
      GEODEX_RETURN_IF_ERROR(MeasureModes(flags, name, pairs, index, unit));
      continue;
    }
    for (int32_t count : flags.samples) {
      GEODEX_ASSIGN_OR_RETURN(auto index, IndexFor(flags, m, name, count, "", {}));
      const auto pairs = validation::DrawPairs(m, index->num_samples(), pair_options);
      GEODEX_RETURN_IF_ERROR(MeasureModes(flags, name, pairs, index, unit));
      if (!flags.error_driven) continue;
      GEODEX_ASSIGN_OR_RETURN(const std::vector<double> weights,
                              PlacementWeights(flags, m, index, count));
      GEODEX_ASSIGN_OR_RETURN(auto placed, IndexFor(flags, m, name, count, "-placed", weights));
      // The same pairs: L differs by the few samples repair adds, so a
      // handful of pairs may sit in a neighbouring bin.
      GEODEX_RETURN_IF_ERROR(MeasureModes(flags, name + " error-driven", pairs, placed, unit));
    }
  }
  return absl::OkStatus();
}

}  // namespace geodex::accuracy
