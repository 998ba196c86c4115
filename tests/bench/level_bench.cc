// level_bench: levels of samples' cost and gain on indexes of one mesh at
// several m (level_measure.h); pure O(1) answers against exact distances:
//   level_bench --mesh M.obj --index m250.gdx --index m1000.gdx --index m4000.gdx

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/mesh/mesh_io.h"
#include "core/query/input_queries.h"
#include "core/validation/pair_sampling.h"
#include "tests/bench/level_measure.h"

namespace geodex::bench {
namespace {

struct Flags {
  std::string mesh;
  std::vector<std::string> indexes;
  validation::PairOptions pairs{.num_sources = 16, .seed = 11, .threads = 2};
  int min_count = 40;
  std::vector<double> radii = {4, 8, 12, 16, 18, 24, 32};
};

absl::StatusOr<std::vector<double>> PureAnswers(const query::InputQueries& queries,
                                                const std::vector<validation::ExactPair>& pairs) {
  std::vector<query::SurfacePoint> a, b;
  for (const validation::ExactPair& p : pairs) a.push_back(p.p), b.push_back(p.q);
  query::EnginePoints ea, eb;
  GEODEX_RETURN_IF_ERROR(queries.Read(a, query::Named("a"), &ea));
  GEODEX_RETURN_IF_ERROR(queries.Read(b, query::Named("b"), &eb));
  std::vector<double> out(pairs.size());
  GEODEX_RETURN_IF_ERROR(
      queries.DistanceBatch(ea, eb, out, {.near_pairs = query::NearPairs::kUnfold}));
  return out;
}

absl::Status Run(const Flags& flags) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh m, mesh::LoadMesh(flags.mesh));
  std::vector<std::shared_ptr<const query::InputQueries>> levels;
  int32_t finest = 0;
  for (const std::string& path : flags.indexes) {
    GEODEX_ASSIGN_OR_RETURN(auto queries, query::InputQueries::Open(path));
    finest = std::max(finest, queries->index().num_samples());
    levels.push_back(std::move(queries));
  }
  const auto pairs = validation::DrawPairs(m, finest, flags.pairs);
  const double l1000 = validation::ScaleLength(m.TotalArea(), 1000);
  std::string ratio = "| m, L/L1000 |", fixed = ratio, sep = "|---|", fsep = sep;
  for (int b = 0; b < kNumRatioBins; ++b) ratio += " d/L " + RatioBinName(b) + " |", sep += "---|";
  for (int b = 0; b < kNumFixedBins; ++b) fixed += " " + FixedBinName(b) + " |", fsep += "---|";
  std::string table =
      "| m | radius / L | neighbours | bytes/sample at 6 B | MiB |\n|---|---|---|---|---|\n";
  ratio += "\n" + sep + "\n";
  fixed += "\n" + fsep + "\n";
  for (const auto& queries : levels) {
    const int32_t count = queries->index().num_samples();
    const double l = queries->scale_length();
    GEODEX_ASSIGN_OR_RETURN(const std::vector<double> answers, PureAnswers(*queries, pairs));
    const LevelErrors e = BinErrors(pairs, answers, l, l1000);
    const std::string label = absl::StrFormat("%d, %.3f", count, l / l1000);
    ratio += RatioRow(label, e, flags.min_count) + "\n";
    fixed += FixedRow(label, e, flags.min_count) + "\n";
    const std::vector<double> n = MeanNeighbours(queries->index(), l, flags.radii);
    for (size_t k = 0; k < n.size(); ++k) {
      const double bytes = TableBytesPerSample(n[k], 6);
      table += absl::StrFormat("| %d | %g | %.0f | %.0f | %.2f |\n", count, flags.radii[k], n[k],
                               bytes, bytes * count / 1048576.0);
    }
  }
  std::printf("%s: %zu pairs; p99 %% vertex / interior of the pure O(1) answer\n\n%s\n%s\n%s",
              flags.mesh.c_str(), pairs.size(), ratio.c_str(), fixed.c_str(), table.c_str());
  return absl::OkStatus();
}

}  // namespace
}  // namespace geodex::bench

int main(int argc, char** argv) {
  CLI::App app{"level_bench: the O(1) error by d/L and neighbour tables' bytes, per index"};
  geodex::bench::Flags flags;
  app.add_option("--mesh", flags.mesh, "The mesh the indexes were built from")->required();
  app.add_option("--index", flags.indexes, "Index files of that mesh (repeat)")->required();
  app.add_option("--sources", flags.pairs.num_sources, "Exact propagations");
  app.add_option("--seed", flags.pairs.seed, "Seed of the pairs (not the builder's)");
  app.add_option("--threads", flags.pairs.threads, "Threads for the propagations");
  app.add_option("--min-count", flags.min_count, "Fewest pairs a bin's p99 is given for");
  app.add_option("--radii", flags.radii, "Radii of the neighbour tables, in L")->delimiter(',');
  CLI11_PARSE(app, argc, argv);
  const absl::Status status = geodex::bench::Run(flags);
  if (status.ok()) return 0;
  std::fprintf(stderr, "level_bench: %s\n", status.ToString().c_str());
  return 2;
}
