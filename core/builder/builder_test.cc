#include "core/builder/builder.h"

#include <filesystem>
#include <fstream>
#include <optional>

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
  // Every vertex record: its distances match an exact propagation from each
  // corner of its triangle.
  geodesic::ExactGeodesicSolver solver(m);
  for (int32_t check : {0, 17, 500, m.num_vertices() - 1}) {
    const index::VertexRecord& r = data->vertices[check];
    ASSERT_GE(r.triangle, 0);
    for (int i = 0; i < 3; ++i) {
      const int32_t sample_vertex = data->samples[data->triangles[r.triangle].corner[i]];
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

// The split for more samples only adds midpoints after the vertices of
// the split for fewer: a target-error build's rounds carry their
// samples (vertex ids) over.
TEST(BuilderTest, SplitForMoreSamplesKeepsTheVerticesOfFewer) {
  const mesh::Mesh coarse = gen::Cube(2, 2.0);  // long edges: every m refines it
  int32_t last_vertices = coarse.num_vertices();
  absl::StatusOr<PreparedMesh> fewer = PrepareMesh(coarse, {}, 40, true);
  ASSERT_TRUE(fewer.ok()) << fewer.status();
  for (int32_t m : {60, 200, 800}) {
    absl::StatusOr<PreparedMesh> more = PrepareMesh(coarse, {}, m, true);
    ASSERT_TRUE(more.ok()) << more.status();
    ASSERT_GT(more->mesh.num_vertices(), fewer->mesh.num_vertices()) << m;
    for (int32_t v = 0; v < fewer->mesh.num_vertices(); ++v) {
      ASSERT_EQ(more->mesh.position(v), fewer->mesh.position(v)) << "m " << m << " vertex " << v;
    }
    EXPECT_GT(more->mesh.num_vertices(), last_vertices);
    last_vertices = more->mesh.num_vertices();
    fewer = std::move(more);
  }
}

// A plan grown from an earlier plan's samples keeps them first, and rows
// carried from the earlier plan give the index that full rows give (to
// rounding: the carried cell distances come from bounded propagations).
TEST(BuilderTest, GrownPlanWithCarriedRowsGivesTheIndexOfFullRows) {
  const mesh::Mesh m = gen::Torus(48, 24, 2.0, 0.7);
  BuildOptions options;
  options.num_samples = 40;
  options.threads = 2;
  absl::StatusOr<Plan> first = MakePlan(m, options);
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_EQ(first->cell_radius.size(), first->samples.size());
  std::vector<int32_t> all_first(first->num_samples());
  for (int32_t a = 0; a < first->num_samples(); ++a) all_first[a] = a;
  absl::StatusOr<std::vector<SampleRow>> first_rows = ComputeRows(m, *first, all_first, options);
  ASSERT_TRUE(first_rows.ok());

  options.num_samples = 90;
  absl::StatusOr<Plan> grown = ExtendPlan(m, first->samples, options);
  ASSERT_TRUE(grown.ok()) << grown.status();
  ASSERT_GE(grown->num_samples(), 90);
  for (int32_t a = 0; a < first->num_samples(); ++a)
    EXPECT_EQ(grown->samples[a], first->samples[a]);
  std::vector<SampleRow> carried = *first_rows;
  for (SampleRow& row : carried) row.to_cell_vertices.clear();

  std::vector<int32_t> all(grown->num_samples());
  for (int32_t a = 0; a < grown->num_samples(); ++a) all[a] = a;
  absl::StatusOr<std::vector<SampleRow>> full = ComputeRows(m, *grown, all, options);
  absl::StatusOr<std::vector<SampleRow>> reused = ComputeRows(m, *grown, all, options, carried);
  ASSERT_TRUE(full.ok() && reused.ok());
  for (int32_t a = 0; a < grown->num_samples(); ++a) {
    const SampleRow& x = (*full)[a];
    const SampleRow& y = (*reused)[a];
    ASSERT_EQ(x.to_cell_vertices.size(), y.to_cell_vertices.size()) << a;
    for (size_t k = 0; k < x.to_cell_vertices.size(); ++k) {
      EXPECT_NEAR(x.to_cell_vertices[k], y.to_cell_vertices[k], 1e-9) << a;
    }
    if (a < first->num_samples()) {
      EXPECT_EQ(y.to_samples.size(), static_cast<size_t>(first->num_samples()));
    } else {
      EXPECT_EQ(y.to_samples, x.to_samples);
    }
  }
  BuildSummary summary_full, summary_reused;
  absl::StatusOr<index::IndexData> a = Merge(m, *grown, *full, &summary_full);
  absl::StatusOr<index::IndexData> b = Merge(m, *grown, *reused, &summary_reused);
  ASSERT_TRUE(a.ok() && b.ok()) << a.status() << b.status();
  ASSERT_EQ(a->sample_distances.size(), b->sample_distances.size());
  for (size_t k = 0; k < a->sample_distances.size(); ++k) {
    EXPECT_NEAR(a->sample_distances[k], b->sample_distances[k], 1e-5) << k;
  }
  // The same triangles but where rounding breaks a tie between two (the
  // torus is symmetric): a vertex lies as far inside either.
  ASSERT_EQ(a->vertices.size(), b->vertices.size());
  size_t other_triangle = 0;
  for (size_t v = 0; v < a->vertices.size(); ++v) {
    EXPECT_NE(b->vertices[v].triangle, mesh::kNone);
    other_triangle += a->vertices[v].triangle != b->vertices[v].triangle;
  }
  EXPECT_LT(other_triangle, a->vertices.size() / 50);
  EXPECT_EQ(summary_full.unassigned_vertices, summary_reused.unassigned_vertices);
  EXPECT_NEAR(summary_full.share_outside, summary_reused.share_outside, 0.002);

  // Carried rows that do not reach their own sample are refused.
  carried = *first_rows;  // moved from by the call above
  carried[3].to_samples.resize(3);
  EXPECT_EQ(ComputeRows(m, *grown, all, options, carried).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ExtendPlan(m, {}, options).status().code(), absl::StatusCode::kInvalidArgument);
  std::vector<int32_t> repeated = {first->samples[0], first->samples[0]};
  EXPECT_EQ(ExtendPlan(m, repeated, options).status().code(), absl::StatusCode::kInvalidArgument);
}

// On a split mesh the rows propagate on the surface before the split, read
// at the samples' and cell vertices' points: the distances of full
// propagations on the split mesh, to rounding, for full rows and for rows
// carried from an earlier plan (bounded propagations).
TEST(BuilderTest, RowsOnTheCoarseSurfaceAreTheSplitMeshRows) {
  const mesh::Mesh coarse = gen::Cube(2, 2.0);  // long edges: every m splits it
  absl::StatusOr<PreparedMesh> prepared = PrepareMesh(coarse, {}, 60, true);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  const mesh::Mesh& m = prepared->mesh;
  absl::StatusOr<std::optional<index::CoarseSurface>> surface = CoarseSurfaceOf(m, prepared->record);
  ASSERT_TRUE(surface.ok()) << surface.status();
  ASSERT_TRUE(surface->has_value());
  ASSERT_EQ((*surface)->mesh.num_vertices(), coarse.num_vertices());
  ASSERT_GT(m.num_vertices(), 4 * coarse.num_vertices());

  BuildOptions options;
  options.num_samples = 30;
  options.threads = 2;
  absl::StatusOr<Plan> first = MakePlan(m, options);
  ASSERT_TRUE(first.ok()) << first.status();
  options.num_samples = 60;
  absl::StatusOr<Plan> plan = ExtendPlan(m, first->samples, options);
  ASSERT_TRUE(plan.ok()) << plan.status();
  std::vector<int32_t> all(plan->num_samples()), all_first(first->num_samples());
  for (int32_t a = 0; a < plan->num_samples(); ++a) all[a] = a;
  for (int32_t a = 0; a < first->num_samples(); ++a) all_first[a] = a;
  absl::StatusOr<std::vector<SampleRow>> split_rows = ComputeRows(m, *plan, all, options);
  absl::StatusOr<std::vector<SampleRow>> coarse_rows =
      ComputeRows(m, *plan, all, options, {}, &**surface);
  absl::StatusOr<std::vector<SampleRow>> carried =
      ComputeRows(m, *first, all_first, options, {}, &**surface);
  ASSERT_TRUE(split_rows.ok() && coarse_rows.ok() && carried.ok());
  for (SampleRow& row : *carried) row.to_cell_vertices.clear();
  absl::StatusOr<std::vector<SampleRow>> reused =
      ComputeRows(m, *plan, all, options, *carried, &**surface);
  ASSERT_TRUE(reused.ok()) << reused.status();
  for (int32_t a = 0; a < plan->num_samples(); ++a) {
    const SampleRow& x = (*split_rows)[a];
    for (const SampleRow* y : {&(*coarse_rows)[a], &(*reused)[a]}) {
      ASSERT_EQ(x.to_cell_vertices.size(), y->to_cell_vertices.size()) << a;
      for (size_t k = 0; k < x.to_cell_vertices.size(); ++k) {
        EXPECT_NEAR(x.to_cell_vertices[k], y->to_cell_vertices[k], 1e-9) << a;
      }
      ASSERT_LE(y->to_samples.size(), x.to_samples.size());
      for (size_t b = 0; b < y->to_samples.size(); ++b) {
        EXPECT_NEAR(x.to_samples[b], y->to_samples[b], 1e-9) << a << " " << b;
      }
    }
  }
  // A coarse surface of another mesh is refused.
  index::CoarseSurface other{coarse, {}};
  EXPECT_EQ(ComputeRows(m, *plan, all, options, {}, &other).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace geodex::builder
