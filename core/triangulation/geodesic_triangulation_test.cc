#include "core/triangulation/geodesic_triangulation.h"

#include <set>
#include <string>

#include "core/mesh/generators.h"
#include "core/triangulation/shapes_testing.h"
#include "gtest/gtest.h"

namespace geodex::triangulation {
namespace {

namespace gen = mesh::gen;

TEST(GeodesicTriangulationTest, RepairReachesAValidTriangulationOnEveryShape) {
  for (TestShape& shape : TestShapes()) {
    SCOPED_TRACE(shape.name);
    auto set = sampling::FarthestPointSampling(shape.mesh, shape.samples, 1);
    ASSERT_TRUE(set.ok());
    RepairReport report;
    auto dual =
        RepairTriangulation(shape.mesh, &*set, {.max_rounds = 200, .max_samples = 2000}, &report);
    ASSERT_TRUE(dual.ok()) << dual.status();
    EXPECT_TRUE(dual->violations.empty());
    EXPECT_FALSE(dual->triangles.empty());
    // Independent re-check of the final labels.
    const DualComplex again =
        CheckDual(shape.mesh, set->nearest, static_cast<int32_t>(set->samples.size()));
    EXPECT_TRUE(again.violations.empty());
    EXPECT_EQ(again.triangles, dual->triangles);
    // Closed surfaces: every triangle has three neighbours.
    if (shape.mesh.num_boundary_edges() == 0) {
      for (const auto& n : dual->neighbors) {
        for (int32_t t : n) EXPECT_GE(t, 0);
      }
      // Euler: V - E + F with E = 3F/2.
      const int64_t f = dual->triangles.size();
      const int64_t v = set->samples.size();
      int64_t chi_mesh = 0;
      chi_mesh =
          shape.mesh.num_vertices() - shape.mesh.num_halfedges() / 2 + shape.mesh.num_faces();
      EXPECT_EQ(v - 3 * f / 2 + f, chi_mesh);
    }
    std::printf("%-18s %4zu samples (%s), %zu triangles\n", shape.name, set->samples.size(),
                report.Summary().c_str(), dual->triangles.size());
  }
}

TEST(GeodesicTriangulationTest, SparseSamplesOnATorusAreDetectedAndRepaired) {
  const mesh::Mesh torus = gen::Torus(64, 32, 2.0, 0.7);
  auto set = sampling::FarthestPointSampling(torus, 4, 1);
  ASSERT_TRUE(set.ok());
  const DualComplex sparse = CheckDual(torus, set->nearest, 4);
  EXPECT_FALSE(sparse.violations.empty());
  RepairReport report;
  auto dual = RepairTriangulation(torus, &*set, {.max_rounds = 200, .max_samples = 2000}, &report);
  ASSERT_TRUE(dual.ok()) << dual.status();
  EXPECT_GT(report.samples_added, 0);
  EXPECT_GT(set->samples.size(), 4u);
}

TEST(GeodesicTriangulationTest, ReportsEachViolationKind) {
  // Two samples on a sphere: two cells touching along one closed arc with no
  // Voronoi vertex, and no triangle at all.
  const mesh::Mesh sphere = gen::Sphere(3, 1.0);
  auto set = sampling::FarthestPointSampling(sphere, 2, 1);
  ASSERT_TRUE(set.ok());
  const DualComplex dual = CheckDual(sphere, set->nearest, 2);
  bool arc = false, not_disk = false;
  for (const Violation& v : dual.violations) {
    arc |= v.kind == ViolationKind::kArcWithoutVertex;
    not_disk |= v.kind == ViolationKind::kCellNotDisk;
  }
  EXPECT_TRUE(arc);
  EXPECT_TRUE(not_disk);
  // A disconnected cell: give cell 0 a vertex deep inside cell 1 (its sample).
  std::vector<int32_t> labels = set->nearest;
  labels[set->samples[1]] = 0;
  bool disconnected = false;
  for (const Violation& v : CheckDual(sphere, labels, 2).violations) {
    disconnected |= v.kind == ViolationKind::kCellDisconnected;
  }
  EXPECT_TRUE(disconnected);
}

TEST(GeodesicTriangulationTest, EveryViolationKindHasANameAndACounter) {
  RepairReport report;
  ASSERT_EQ(report.added_for.size(), static_cast<size_t>(kNumViolationKinds));
  std::set<std::string> names;
  for (int k = 0; k < kNumViolationKinds; ++k) {
    const std::string name = ViolationName(static_cast<ViolationKind>(k));
    EXPECT_NE(name, "?");
    names.insert(name);
    report.added_for[k] = k + 1;
  }
  EXPECT_EQ(names.size(), static_cast<size_t>(kNumViolationKinds));
  EXPECT_EQ(static_cast<int>(ViolationKind::kEdgesCross), kNumViolationKinds - 1);
  const std::string summary = report.Summary();
  EXPECT_NE(summary.find("1 for three cells meeting more than once"), std::string::npos);
  EXPECT_NE(summary.find("9 for geodesic edges crossing"), std::string::npos);
}

TEST(GeodesicTriangulationTest, FailsCleanlyWhenRepairIsCapped) {
  const mesh::Mesh torus = gen::Torus(64, 32, 2.0, 0.7);
  auto set = sampling::FarthestPointSampling(torus, 3, 1);
  ASSERT_TRUE(set.ok());
  RepairReport report;
  auto dual = RepairTriangulation(torus, &*set, {.max_rounds = 1, .max_samples = 4}, &report);
  EXPECT_EQ(dual.status().code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace geodex::triangulation
