// A scan that passes through itself, as the builder gets it: two sheets
// crossing along an edge shared by four faces in crossing orientations
// (broken_meshes_testing.h), read from an OBJ file, repaired, built into an
// index as geodex-build builds it, and answered in the file's ids.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/common/file_util.h"
#include "core/index/index.h"
#include "core/mesh/broken_meshes_testing.h"
#include "core/mesh/mesh_repair.h"
#include "core/query/input_queries.h"
#include "core/query/engine/query_engine.h"
#include "gtest/gtest.h"

namespace geodex {
namespace {

using mesh::RawMesh;
using mesh::SurfacePoint;
using mesh::Vec3;

std::string ObjText(const RawMesh& raw) {
  std::string out;
  for (const Vec3& p : raw.positions)
    absl::StrAppendFormat(&out, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
  for (const mesh::Triangle& t : raw.triangles) {
    absl::StrAppendFormat(&out, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  return out;
}

Vec3 PositionOf(const RawMesh& raw, const SurfacePoint& p) {
  const mesh::Triangle& t = raw.triangles[p.face];
  return p.w[0] * raw.positions[t[0]] + p.w[1] * raw.positions[t[1]] + p.w[2] * raw.positions[t[2]];
}

// geodex-build's steps on the mesh file at `path`: repair, refine, build,
// with the float32 matrix, whose straight answers are exact to its
// rounding; the index's queries in the file's ids.
void BuildAsGeodexBuild(const std::string& path, int32_t samples,
                        std::shared_ptr<const query::InputQueries>* out) {
  absl::StatusOr<mesh::RepairedMesh> repaired = mesh::LoadAndRepairMesh(path);
  ASSERT_TRUE(repaired.ok()) << repaired.status();
  EXPECT_EQ(repaired->report.nonmanifold_edges, 1);
  EXPECT_EQ(repaired->report.edge_copies, 2);
  EXPECT_EQ(repaired->mesh.num_components(), 2);
  absl::StatusOr<builder::PreparedMesh> prepared = builder::PrepareMesh(
      repaired->mesh, builder::RecordRepair(*repaired), samples, /*refine=*/true);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  builder::BuildOptions options;
  options.num_samples = samples;
  options.threads = 2;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data = builder::BuildPreparedIndex(*prepared, options, &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  EXPECT_EQ(summary.unassigned_vertices, 0);
  EXPECT_NE(data->report.find("mesh_nonmanifold_edges_cut = 1\n"), std::string::npos);
  // The float32 matrix: the straight answers are exact to its rounding.
  data->sample_matrix = index::MatrixLayout::kFull;
  absl::StatusOr<std::string> bytes = index::SerializeIndex(*data);
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  auto index = index::Index::FromBytes(*std::move(bytes));
  ASSERT_TRUE(index.ok()) << index.status();
  absl::StatusOr<std::shared_ptr<const query::QueryEngine>> engine =
      query::QueryEngine::Create(*std::move(index));
  ASSERT_TRUE(engine.ok()) << engine.status();
  absl::StatusOr<std::shared_ptr<const query::InputQueries>> queries =
      query::InputQueries::Create(*engine);
  ASSERT_TRUE(queries.ok()) << queries.status();
  *out = *std::move(queries);
}

// Random points of one sheet (faces [sheet, sheet + 1) * faces_per_sheet),
// in a face drawn uniformly, area-uniform in it.
class SheetPoints {
 public:
  explicit SheetPoints(int32_t faces_per_sheet) : faces_per_sheet_(faces_per_sheet) {}

  SurfacePoint operator()(int sheet) {
    SurfacePoint p;
    p.face = sheet * faces_per_sheet_ +
             std::uniform_int_distribution<int32_t>(0, faces_per_sheet_ - 1)(rng_);
    double u = unit_(rng_), v = unit_(rng_);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    p.w = {1 - u - v, u, v};
    return p;
  }

 private:
  int32_t faces_per_sheet_;
  std::mt19937_64 rng_{5};
  std::uniform_real_distribution<double> unit_{0, 1};
};

// Pairs within each flat square sheet, in the file's face ids, including
// points on the shared edge's ends: the answer is the straight line.
void SheetPairs(const RawMesh& raw, int32_t faces_per_sheet, SheetPoints& random_point,
                std::vector<SurfacePoint>* a, std::vector<SurfacePoint>* b) {
  for (int sheet = 0; sheet < 2; ++sheet) {
    for (int k = 0; k < 200; ++k) {
      a->push_back(random_point(sheet));
      b->push_back(random_point(sheet));
    }
    // From the shared edge's end a (vertex 0), in every face of this sheet
    // round it.
    for (int32_t f = sheet * faces_per_sheet; f < (sheet + 1) * faces_per_sheet; ++f) {
      const mesh::Triangle& t = raw.triangles[f];
      for (int i = 0; i < 3; ++i) {
        if (t[i] != 0) continue;
        SurfacePoint at_a{f, {0, 0, 0}};
        at_a.w[i] = 1;
        for (int k = 0; k < 10; ++k) {
          a->push_back(at_a);
          b->push_back(random_point(sheet));
        }
      }
    }
  }
}

TEST(CrossingSheetsBuildTest, ScanCrossingItselfBuildsAndAnswers) {
  const int n = 8;
  const RawMesh raw = mesh::testing::TwoSheetsCrossingAlongAnEdge(n);
  const int32_t faces_per_sheet = static_cast<int32_t>(raw.triangles.size()) / 2;
  const std::string path =
      (std::filesystem::temp_directory_path() / "geodex_crossing_sheets.obj").string();
  ASSERT_TRUE(AtomicWriteFile(path, ObjText(raw)).ok());

  std::shared_ptr<const query::InputQueries> queries;
  ASSERT_NO_FATAL_FAILURE(BuildAsGeodexBuild(path, /*samples=*/60, &queries));
  EXPECT_EQ(queries->num_faces(), static_cast<int32_t>(raw.triangles.size()));

  SheetPoints random_point(faces_per_sheet);
  std::vector<SurfacePoint> a, b;
  SheetPairs(raw, faces_per_sheet, random_point, &a, &b);
  query::EnginePoints ea, eb;
  ASSERT_TRUE(queries->Read(a, query::Named("a"), &ea).ok());
  ASSERT_TRUE(queries->Read(b, query::Named("b"), &eb).ok());
  std::vector<double> d(a.size());
  ASSERT_TRUE(queries->DistanceBatch(ea, eb, d).ok());
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double straight = (PositionOf(raw, a[i]) - PositionOf(raw, b[i])).norm();
    ASSERT_TRUE(std::isfinite(d[i])) << i;
    worst = std::max(worst, std::abs(d[i] - straight) / std::max(straight, 1.0 / n));
  }
  std::printf("crossing sheets: %zu pairs, worst error %.3g of the distance (or of an edge)\n",
              a.size(), worst);
  EXPECT_LT(worst, 1e-5);

  // The sheets no longer touch: no path leads from one to the other.
  const std::vector<SurfacePoint> on_a = {random_point(0)}, on_b = {random_point(1)};
  ASSERT_TRUE(queries->Read(on_a, query::Named("a"), &ea).ok());
  ASSERT_TRUE(queries->Read(on_b, query::Named("b"), &eb).ok());
  const absl::StatusOr<double> across = queries->Distance(ea, 0, eb, 0);
  EXPECT_TRUE(!across.ok() || !std::isfinite(*across)) << *across;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace geodex
