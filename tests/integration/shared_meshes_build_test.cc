// The builder on every development mesh in ../shared/meshes (skipped when the
// directory is absent): the plan (sampling and the repaired geodesic Delaunay
// triangulation) must be valid everywhere; meshes up to 7000 vertices also get
// a full index whose vertices must all be assigned. Meshes are repaired as
// geodex-build repairs them (core/mesh/mesh_repair.h): cow_nonmanifold_3k has
// its non-manifold vertex split, and is refused clearly when strict. Meshes over 50000 vertices
// (igea_134k) run only with GEODEX_LARGE_TESTS=1.

#include <cstdlib>
#include <filesystem>

#include "core/builder/builder.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_repair.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex {
namespace {

std::string SharedDir() {
  const char* env = std::getenv("GEODEX_SHARED_MESHES");
  return env != nullptr ? env : GEODEX_SHARED_MESHES_DEFAULT;
}

std::vector<std::string> SharedMeshes() {
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(SharedDir(), error)) {
    if (entry.path().extension() == ".obj") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  if (names.empty()) names.push_back("none");
  return names;
}

class SharedMeshBuildTest : public ::testing::TestWithParam<std::string> {};

TEST_P(SharedMeshBuildTest, PlanIsValidAndSmallMeshesIndexCompletely) {
  if (GetParam() == "none") {
    GTEST_SKIP() << "no meshes in " << SharedDir()
                 << " (set GEODEX_SHARED_MESHES to the development meshes)";
  }
  const std::string path = SharedDir() + "/" + GetParam() + ".obj";
  auto repaired = mesh::LoadAndRepairMesh(path);
  ASSERT_TRUE(repaired.ok()) << repaired.status();
  if (GetParam() == "cow_nonmanifold_3k") {
    EXPECT_EQ(repaired->report.nonmanifold_vertices, 1);
    mesh::RepairOptions strict;
    strict.strict = true;
    const auto refused = mesh::LoadAndRepairMesh(path, strict);
    ASSERT_FALSE(refused.ok());
    EXPECT_THAT(refused.status().message(), ::testing::HasSubstr("non-manifold vertex"));
  } else {
    EXPECT_FALSE(repaired->report.changed()) << repaired->report.Summary();
  }
  const mesh::Mesh* mesh = &repaired->mesh;
  if (mesh->num_vertices() > 50000 && std::getenv("GEODEX_LARGE_TESTS") == nullptr) {
    GTEST_SKIP() << GetParam() << " has " << mesh->num_vertices()
                 << " vertices; set GEODEX_LARGE_TESTS=1 to include it (minutes)";
  }
  builder::BuildOptions options;
  options.num_samples = 150;
  options.threads = 2;
  auto plan = builder::MakePlan(*mesh, options);
  ASSERT_TRUE(plan.ok()) << plan.status();
  const auto dual = triangulation::CheckDual(*mesh, plan->nearest, plan->num_samples());
  EXPECT_TRUE(dual.violations.empty());
  std::printf("%s: %d samples (%s), %zu triangles\n", GetParam().c_str(), plan->num_samples(),
              plan->repair.Summary().c_str(), plan->triangles.size());
  if (mesh->num_vertices() > 7000) return;  // full rows cost minutes on big meshes
  std::vector<int32_t> all(plan->num_samples());
  for (int32_t a = 0; a < plan->num_samples(); ++a) all[a] = a;
  auto rows = builder::ComputeRows(*mesh, *plan, all, options);
  ASSERT_TRUE(rows.ok()) << rows.status();
  builder::BuildSummary summary;
  auto data = builder::Merge(*mesh, *plan, std::move(*rows), &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  EXPECT_EQ(summary.unassigned_vertices, 0);
  std::printf("%s", summary.ToText().c_str());
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, SharedMeshBuildTest, ::testing::ValuesIn(SharedMeshes()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace geodex
