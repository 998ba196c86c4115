// The long-edge split on a coarse mesh, measured as users see it: pairs in
// the input's ids, the O(1) answer against exact distances. Samples are
// vertices, so without the split a coarse mesh caps m at its vertex count
// and its geodesic triangles at its edge lengths; with it, the error keeps
// falling as m grows past the vertex count.

#include <cmath>
#include <vector>

#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/mesh/generators.h"
#include "core/query/engine/input_ids.h"
#include "core/query/engine/query_engine.h"
#include "core/validation/pair_sampling.h"
#include "gtest/gtest.h"

namespace geodex::validation {
namespace {

struct Measured {
  int32_t samples = 0;    // after the triangulation's repair
  int32_t midpoints = 0;  // added by the split
  double rms = 0;         // relative, area-uniform pairs, pure O(1) answer
};

// Builds `coarse` for `m` samples as geodex-build does (split or not) and
// measures the pure O(1) answer on `pairs` (in `coarse`'s ids).
Measured Measure(const mesh::Mesh& coarse, int32_t m, bool split,
                 const std::vector<ExactPair>& pairs) {
  absl::StatusOr<builder::PreparedMesh> prepared = builder::PrepareMesh(coarse, {}, m, split);
  EXPECT_TRUE(prepared.ok()) << prepared.status();
  builder::BuildOptions options;
  options.num_samples = m;
  options.threads = 2;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data = builder::BuildPreparedIndex(*prepared, options, &summary);
  EXPECT_TRUE(data.ok()) << data.status();
  auto index = index::Index::FromBytes(*index::SerializeIndex(*data));
  EXPECT_TRUE(index.ok()) << index.status();
  auto engine = query::QueryEngine::Create(*index);
  EXPECT_TRUE(engine.ok()) << engine.status();
  const query::InputIds ids((*engine)->index());
  query::DistanceOptions unfold;
  unfold.near_pairs = query::NearPairs::kUnfold;
  double sum = 0;
  int count = 0;
  for (const ExactPair& pair : pairs) {
    if (!pair.uniform || pair.exact <= 0) continue;
    const double d = *(*engine)->Distance(*ids.ToInternal(pair.p), *ids.ToInternal(pair.q), unfold);
    const double e = (d - pair.exact) / pair.exact;
    sum += e * e;
    ++count;
  }
  return {(*index)->num_samples(), (*index)->split_vertices(), std::sqrt(sum / count)};
}

TEST(LongEdgeSplitAccuracyTest, ErrorFallsWithSamplesPastTheVertexCountOfACoarseMesh) {
  // A coarse torus: 128 vertices, edges 0.55 and 0.79 long.
  const mesh::Mesh torus = mesh::gen::Torus(16, 8, 2.0, 0.7);
  const std::vector<ExactPair> pairs = DrawPairs(
      torus, 100,
      {.num_sources = 8, .uniform_points = 200, .per_bin_points = 0, .seed = 5, .threads = 2});
  std::vector<Measured> split;
  for (int32_t m : {50, 100, 200, 400}) {
    split.push_back(Measure(torus, m, /*split=*/true, pairs));
    const Measured& r = split.back();
    std::printf("split m=%d: %d samples, %d midpoints, relative RMS %.3f%%\n", m, r.samples,
                r.midpoints, 100 * r.rms);
  }
  const Measured unsplit = Measure(torus, 100, /*split=*/false, pairs);
  std::printf("unsplit m=100: %d samples, relative RMS %.3f%%\n", unsplit.samples,
              100 * unsplit.rms);
  // The torus's own vertices cannot hold many more samples than this.
  EXPECT_LE(unsplit.samples, torus.num_vertices());
  EXPECT_GT(split.back().samples, 2 * torus.num_vertices());
  for (size_t i = 1; i < split.size(); ++i) {
    EXPECT_LT(split[i].rms, 0.9 * split[i - 1].rms) << i;
    EXPECT_GT(split[i].midpoints, split[i - 1].midpoints) << i;
  }
  EXPECT_LT(split.back().rms, 0.5 * unsplit.rms);
}

}  // namespace
}  // namespace geodex::validation
