#include "core/builder/builder.h"

#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "core/builder/workdir.h"
#include "core/mesh/generators.h"
#include "gtest/gtest.h"

namespace geodex::builder {
namespace {

namespace gen = mesh::gen;

std::string TempDir(const std::string& name) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("geodex_builder_test_" + name)).string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

absl::StatusOr<std::string> BuildBytes(const mesh::Mesh& m, int32_t samples, int threads) {
  BuildOptions options;
  options.num_samples = samples;
  options.seed = 3;
  options.threads = threads;
  BuildSummary summary;
  auto data = BuildIndex(m, options, &summary);
  if (!data.ok()) return data.status();
  return index::SerializeIndex(*data);
}

TEST(BuilderTest, SphereIndexIsValidAndComplete) {
  const mesh::Mesh m = gen::Sphere(4, 1.0);
  BuildOptions options;
  options.num_samples = 80;
  options.threads = 2;
  BuildSummary summary;
  auto data = BuildIndex(m, options, &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  EXPECT_EQ(summary.unassigned_vertices, 0);
  EXPECT_LT(summary.share_outside, 0.01);
  EXPECT_GT(summary.longest_edge, 0);
  const int32_t ms = data->params.num_samples;
  ASSERT_EQ(data->sample_distances.size(), static_cast<size_t>(ms) * ms);
  for (int32_t a = 0; a < ms; ++a) {
    EXPECT_EQ(data->sample_distances[a * ms + a], 0.0f);
    for (int32_t b = 0; b < ms; ++b) {
      EXPECT_EQ(data->sample_distances[a * ms + b], data->sample_distances[b * ms + a]);
    }
  }
  // Every vertex record: its corners form its triangle, and its distances
  // match an exact propagation from each corner.
  geodesic::ExactGeodesicSolver solver(m);
  for (int32_t check : {0, 17, 500, m.num_vertices() - 1}) {
    const index::VertexRecord& r = data->vertices[check];
    ASSERT_GE(r.triangle, 0);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(r.corner[i], data->triangles[r.triangle].corner[i]);
      const int32_t sample_vertex = data->samples[r.corner[i]];
      ASSERT_TRUE(solver.Propagate({*mesh::VertexPoint(m, sample_vertex)}).ok());
      EXPECT_NEAR(r.distance[i], solver.VertexDistance(check), 1e-6);
    }
  }
  auto bytes = index::SerializeIndex(*data);
  ASSERT_TRUE(bytes.ok());
  auto loaded = index::Index::FromBytes(*bytes);
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_NE((*loaded)->report().find("unassigned_vertices = 0"), std::string::npos);
}

TEST(BuilderTest, ByteIdenticalAcrossThreadCounts) {
  const mesh::Mesh m = gen::Torus(48, 24, 2.0, 0.7);
  auto one = BuildBytes(m, 50, 1);
  auto two = BuildBytes(m, 50, 2);
  auto three = BuildBytes(m, 50, 3);
  ASSERT_TRUE(one.ok() && two.ok() && three.ok()) << one.status();
  EXPECT_EQ(*one, *two);
  EXPECT_EQ(*one, *three);
}

TEST(BuilderTest, ShardedBuildIsByteIdenticalToOneProcess) {
  const mesh::Mesh m = gen::Torus(48, 24, 2.0, 0.7);
  auto single = BuildBytes(m, 50, 2);
  ASSERT_TRUE(single.ok());

  const std::string dir = TempDir("sharded");
  BuildOptions options;
  options.num_samples = 50;
  options.seed = 3;
  options.threads = 1;
  auto plan = MakePlan(m, options);
  ASSERT_TRUE(plan.ok());
  ASSERT_TRUE(SavePlan(m, *plan, dir).ok());
  EXPECT_EQ(LoadAllRows(*plan, dir).status().code(), absl::StatusCode::kNotFound);
  for (int32_t shard = 0; shard < 3; ++shard) {
    auto loaded = LoadPlan(dir);  // as a separate machine would
    ASSERT_TRUE(loaded.ok()) << loaded.status();
    const auto& [mesh2, plan2] = *loaded;
    auto rows = ComputeRows(mesh2, plan2, ShardSamples(plan2.num_samples(), shard, 3), options);
    ASSERT_TRUE(rows.ok());
    ASSERT_TRUE(SaveRows(plan2, *rows, shard, 3, dir).ok());
    if (shard == 1) {  // a missing shard is reported
      EXPECT_EQ(LoadAllRows(plan2, dir).status().code(), absl::StatusCode::kNotFound);
    }
  }
  auto loaded = LoadPlan(dir);
  ASSERT_TRUE(loaded.ok());
  auto rows = LoadAllRows(loaded->second, dir);
  ASSERT_TRUE(rows.ok()) << rows.status();
  BuildSummary summary;
  auto data = Merge(loaded->first, loaded->second, std::move(*rows), &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  auto bytes = index::SerializeIndex(*data);
  ASSERT_TRUE(bytes.ok());
  EXPECT_EQ(*bytes, *single);

  // A corrupted shard file is rejected, not merged.
  const std::string shard_path = dir + "/rows-00001-of-00003.bin";
  {
    std::fstream f(shard_path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(40);
    f.put('\x7f');
  }
  EXPECT_EQ(LoadAllRows(loaded->second, dir).status().code(), absl::StatusCode::kDataLoss);
  std::filesystem::remove_all(dir);
}

TEST(BuilderTest, PlanTracesTheEdgesAndTheWorkDirectoryKeepsTheirFigures) {
  const mesh::Mesh m = gen::Torus(48, 24, 2.0, 0.7);
  BuildOptions options;
  options.num_samples = 50;
  options.threads = 2;
  auto plan = MakePlan(m, options);
  ASSERT_TRUE(plan.ok()) << plan.status();
  const size_t num_edges = triangulation::DelaunayEdges(plan->triangles).size();
  ASSERT_EQ(plan->edges.size(), num_edges);
  EXPECT_EQ(plan->edge_stats.count, static_cast<int32_t>(num_edges));
  EXPECT_GT(plan->edge_stats.longest, 0);
  EXPECT_LT(plan->edge_stats.max_relative_error, 1e-9);

  const std::string dir = TempDir("edges");
  ASSERT_TRUE(SavePlan(m, *plan, dir).ok());
  auto loaded = LoadPlan(dir);
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  const Plan& again = loaded->second;
  EXPECT_TRUE(again.edges.empty());  // the paths stay in the planning process
  EXPECT_EQ(again.edge_stats.count, plan->edge_stats.count);
  EXPECT_EQ(again.edge_stats.total_length, plan->edge_stats.total_length);
  EXPECT_EQ(again.edge_stats.longest, plan->edge_stats.longest);
  EXPECT_EQ(again.repair.crossings_found, plan->repair.crossings_found);
  EXPECT_EQ(again.repair.added_for, plan->repair.added_for);

  std::vector<int32_t> all(again.num_samples());
  for (int32_t a = 0; a < again.num_samples(); ++a) all[a] = a;
  auto rows = ComputeRows(loaded->first, again, all, options);
  ASSERT_TRUE(rows.ok());
  BuildSummary summary;
  auto data = Merge(loaded->first, again, std::move(*rows), &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  EXPECT_EQ(summary.geodesic_edges, static_cast<int32_t>(num_edges));
  EXPECT_EQ(summary.edge_length_max, plan->edge_stats.longest);
  EXPECT_NE(data->report.find(absl::StrCat("geodesic_edges = ", num_edges, "\n")),
            std::string::npos);
  EXPECT_NE(data->report.find("edge_crossings_found = "), std::string::npos);

  // A plan file of the previous format version is refused, not misread.
  {
    std::fstream f(dir + "/plan.bin", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(7);
    f.put('1');
  }
  EXPECT_EQ(LoadPlan(dir).status().code(), absl::StatusCode::kFailedPrecondition);
  std::filesystem::remove_all(dir);

  options.check_edges = false;
  auto unchecked = MakePlan(m, options);
  ASSERT_TRUE(unchecked.ok());
  EXPECT_TRUE(unchecked->edges.empty());
  EXPECT_EQ(unchecked->edge_stats.count, 0);
}

TEST(BuilderTest, MeshWithBoundaryAndTwoComponents) {
  for (const mesh::Mesh& m : {gen::SquareWithHole(30, 3.0), gen::TwoComponents(12)}) {
    BuildOptions options;
    options.num_samples = 40;
    options.threads = 2;
    BuildSummary summary;
    auto data = BuildIndex(m, options, &summary);
    ASSERT_TRUE(data.ok()) << data.status();
    EXPECT_EQ(summary.unassigned_vertices, 0);
    std::printf("%s: %s", m.name().c_str(), summary.ToText().c_str());
  }
}

TEST(BuilderTest, MergeRejectsMissingRows) {
  const mesh::Mesh m = gen::Sphere(2, 1.0);
  BuildOptions options;
  options.num_samples = 12;
  auto plan = MakePlan(m, options);
  ASSERT_TRUE(plan.ok());
  std::vector<int32_t> some = {0, 1, 2};
  auto rows = ComputeRows(m, *plan, some, options);
  ASSERT_TRUE(rows.ok());
  BuildSummary summary;
  EXPECT_EQ(Merge(m, *plan, *rows, &summary).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace geodex::builder
