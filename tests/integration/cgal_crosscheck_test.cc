// Cross-check of ExactGeodesicSolver (and, from vertex sources, of
// VertexGeodesicSolver, the builder's wavefront engine) against an
// independent exact algorithm, CGAL's Surface_mesh_shortest_path (CGAL 5.5.1, Exact_predicates_inexact_
// constructions_kernel, Surface_mesh): distances at EVERY vertex must agree to
// a relative difference of kMaxRelativeDifference.
//
// CGAL 5.5.1 pitfalls worked around here (measured by us; see
// cgal_reference.h for how the wrapper handles each):
//  (1) a source exactly on an edge is placed at its mirror image along the
//      edge: sources are only at vertices, strictly inside faces, and at exact
//      edge midpoints (their own mirror image);
//  (2) for a face added as (v0, v1, v2) CGAL's barycentric order is
//      (v2, v0, v1): the wrapper converts face-location sources, and
//      BarycentricOrderIsV2V0V1 / SourceNearACornerIsNearThatCorner check it;
//  (3) unreferenced vertices crash CGAL: the CGAL mesh is built from the
//      referenced vertices only and only those are compared; ours must report
//      +inf at unreferenced vertices (checked);
//  (4) a sequence tree needs ~9 GB on igea_134k: meshes with >= kMaxVertices
//      vertices are skipped.
//
// Shared meshes: every .obj/.ply/.off file in $GEODEX_SHARED_MESHES (else the
// compile-time GEODEX_SHARED_MESHES_DEFAULT) becomes one test, listed when the
// tests are discovered. Two sources per mesh (a vertex and a face interior)
// keep the run short: CGAL takes ~4-7 s per source on a 30k-vertex mesh.

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/geodesic/vertex_geodesic.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/integration/cgal_reference.h"

namespace geodex {
namespace {

using cgal_reference::CgalShortestPaths;
using geodesic::ExactGeodesicSolver;
using mesh::Mesh;
using mesh::SurfacePoint;
using mesh::Vec3;
namespace gen = mesh::gen;
using ::testing::HasSubstr;

constexpr double kMaxRelativeDifference = 1e-6;
constexpr int32_t kMaxVertices = 50000;  // pitfall (4)

struct NamedSource {
  std::string name;
  SurfacePoint point;
  int32_t vertex = mesh::kNone;  // set for a vertex source: the wavefront engine runs too
};

// |a - b| relative to the larger of the two; 0 when both are 0 or both +inf.
double RelativeDifference(double a, double b) {
  if (a == b) return 0;
  if (std::isinf(a) || std::isinf(b)) return std::numeric_limits<double>::infinity();
  return std::abs(a - b) / std::max(std::abs(a), std::abs(b));
}

// A referenced vertex near id `v` (searching upwards, wrapping around).
int32_t ReferencedVertexFrom(const Mesh& m, int32_t v) {
  for (int32_t k = 0; k < m.num_vertices(); ++k) {
    const int32_t u = (v + k) % m.num_vertices();
    if (m.IsReferenced(u)) return u;
  }
  return mesh::kNone;
}

SurfacePoint AtVertex(const Mesh& m, int32_t v) { return *mesh::VertexPoint(m, v); }

// A generic point strictly inside face f.
SurfacePoint InsideFace(int32_t f) { return {f, {0.2, 0.3, 0.5}}; }

// The exact midpoint of an interior edge (one with a twin), searching faces
// from `f` upwards; pitfall (1) allows no other edge point.
SurfacePoint InteriorEdgeMidpoint(const Mesh& m, int32_t f) {
  for (int32_t k = 0; k < m.num_faces(); ++k) {
    const int32_t g = (f + k) % m.num_faces();
    for (int i = 0; i < 3; ++i) {
      if (m.Twin(3 * g + i) == mesh::kNone) continue;
      SurfacePoint p{g, {0, 0, 0}};
      p.w[i] = 0.5;
      p.w[(i + 1) % 3] = 0.5;
      return p;
    }
  }
  return {f, {0.5, 0.5, 0}};
}

struct Agreement {
  double max_relative = 0;
  double wavefront_max_relative = 0;  // vertex sources only
  int compared = 0;  // vertices times sources
  double ours_seconds = 0;
  double cgal_seconds = 0;
};

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Runs ours and CGAL from each source and compares every vertex.
Agreement CheckAgreement(const Mesh& m, const std::vector<NamedSource>& sources) {
  Agreement result;
  auto cgal = CgalShortestPaths::Create(m);
  if (!cgal.ok()) {
    ADD_FAILURE() << cgal.status();
    return result;
  }
  ExactGeodesicSolver solver(m);
  geodesic::VertexGeodesicSolver wavefront(m);
  for (const NamedSource& source : sources) {
    SCOPED_TRACE(source.name);
    auto start = std::chrono::steady_clock::now();
    const absl::Status status = solver.Propagate({source.point});
    result.ours_seconds += Seconds(start);
    if (!status.ok()) {
      ADD_FAILURE() << status;
      continue;
    }
    start = std::chrono::steady_clock::now();
    const absl::StatusOr<std::vector<double>> reference = (*cgal)->Distances(source.point);
    result.cgal_seconds += Seconds(start);
    (*cgal)->Release();
    if (!reference.ok()) {
      ADD_FAILURE() << reference.status();
      continue;
    }
    double worst = 0;
    int32_t worst_vertex = mesh::kNone;
    for (int32_t v = 0; v < m.num_vertices(); ++v) {
      const double ours = solver.VertexDistance(v);
      if (!m.IsReferenced(v)) {  // pitfall (3): CGAL never saw it
        EXPECT_EQ(ours, geodesic::kInfinity) << "unreferenced vertex " << v;
        continue;
      }
      const double rel = RelativeDifference(ours, (*reference)[v]);
      ++result.compared;
      if (rel > worst || worst_vertex == mesh::kNone) {
        worst = rel;
        worst_vertex = v;
      }
    }
    if (worst_vertex == mesh::kNone) {
      ADD_FAILURE() << "no vertex compared";
      continue;
    }
    EXPECT_LE(worst, kMaxRelativeDifference)
        << "worst at vertex " << worst_vertex << ": ours " << solver.VertexDistance(worst_vertex)
        << ", CGAL " << (*reference)[worst_vertex];
    result.max_relative = std::max(result.max_relative, worst);
    if (source.vertex == mesh::kNone) continue;
    if (const absl::Status status = wavefront.Propagate({source.vertex}); !status.ok()) {
      ADD_FAILURE() << "wavefront: " << status;
      continue;
    }
    double wavefront_worst = 0;
    int32_t wavefront_worst_vertex = mesh::kNone;
    for (int32_t v = 0; v < m.num_vertices(); ++v) {
      if (!m.IsReferenced(v)) continue;
      const double rel = RelativeDifference(wavefront.VertexDistance(v), (*reference)[v]);
      if (rel > wavefront_worst || wavefront_worst_vertex == mesh::kNone) {
        wavefront_worst = rel;
        wavefront_worst_vertex = v;
      }
    }
    EXPECT_LE(wavefront_worst, kMaxRelativeDifference)
        << "wavefront engine, worst at vertex " << wavefront_worst_vertex << ": "
        << wavefront.VertexDistance(wavefront_worst_vertex) << ", CGAL "
        << (*reference)[wavefront_worst_vertex];
    result.wavefront_max_relative = std::max(result.wavefront_max_relative, wavefront_worst);
  }
  return result;
}

void Report(const std::string& label, const Mesh& m, size_t num_sources, const Agreement& a) {
  ::testing::Test::RecordProperty("max_relative_difference",
                                  absl::StrFormat("%.3g", a.max_relative));
  ::testing::Test::RecordProperty("vertices", m.num_vertices());
  std::printf(
      "[ cgal     ] %s: max relative difference %.3g over %d vertex distances (%d vertices, %zu "
      "sources), wavefront engine %.3g; ours %.3f s, CGAL %.3f s\n",
      label.c_str(), a.max_relative, a.compared, m.num_vertices(), num_sources,
      a.wavefront_max_relative, a.ours_seconds, a.cgal_seconds);
  std::fflush(stdout);
}

// ============================================================================
// The wrapper itself: pitfall (2).

TEST(CgalReferenceTest, BarycentricOrderIsV2V0V1) {
  const Mesh m = gen::Sphere(2, 1.0);
  auto cgal = CgalShortestPaths::Create(m);
  ASSERT_TRUE(cgal.ok()) << cgal.status();
  for (int32_t f = 0; f < m.num_faces(); ++f) {
    const mesh::Triangle& t = m.face(f);
    const std::array<int32_t, 3> expected = {t[2], t[0], t[1]};
    ASSERT_EQ((*cgal)->BarycentricOrder(f), expected) << "face " << f;
  }
}

// A face source close to one corner must be close to that corner for CGAL too:
// a wrong conversion of barycentric order would put it near another corner.
TEST(CgalReferenceTest, SourceNearACornerIsNearThatCorner) {
  const Mesh m = gen::Grid(8, 8, 1.0, 1.0, 0.2, 3);
  auto cgal = CgalShortestPaths::Create(m);
  ASSERT_TRUE(cgal.ok()) << cgal.status();
  const int32_t f = m.num_faces() / 2;
  for (int corner = 0; corner < 3; ++corner) {
    SurfacePoint p{f, {0.01, 0.01, 0.01}};
    p.w[corner] = 0.98;
    const absl::StatusOr<std::vector<double>> d = (*cgal)->Distances(p);
    ASSERT_TRUE(d.ok()) << d.status();
    const double expected = (PositionOf(m, p) - m.position(m.face(f)[corner])).norm();
    EXPECT_NEAR((*d)[m.face(f)[corner]], expected, 1e-12) << "corner " << corner;
  }
}

TEST(CgalReferenceTest, RejectsEdgePointsOtherThanMidpoints) {
  const Mesh m = gen::Grid(4, 4, 1.0, 1.0);
  auto cgal = CgalShortestPaths::Create(m);
  ASSERT_TRUE(cgal.ok()) << cgal.status();
  const absl::StatusOr<std::vector<double>> d = (*cgal)->Distances({0, {0.3, 0.7, 0}});
  EXPECT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(d.status().message(), HasSubstr("midpoint"));
}

// ============================================================================
// Generated meshes: always run (CI).

struct GeneratedCase {
  std::string name;
  Mesh (*make)();
};
// Names the case in test listings (ctest shows GetParam()).
void PrintTo(const GeneratedCase& c, std::ostream* os) { *os << c.name; }

// Grid with three unreferenced vertices: pitfall (3).
Mesh GridWithUnreferencedVertices() {
  const Mesh grid = gen::Grid(12, 10, 1.2, 1.0, 0.3, 5);
  std::vector<Vec3> positions;
  positions.push_back(Vec3(5, 5, 5));  // unreferenced, before every other vertex
  positions.insert(positions.end(), grid.positions().begin(), grid.positions().end());
  positions.push_back(Vec3(-5, 0, 0));
  positions.push_back(Vec3(0.5, 0.5, 0));  // on the surface, yet in no face
  std::vector<mesh::Triangle> faces = grid.faces();
  for (mesh::Triangle& t : faces) {
    for (int32_t& v : t) ++v;
  }
  return *Mesh::Create(std::move(positions), std::move(faces), "grid_with_unreferenced");
}

const GeneratedCase kGeneratedCases[] = {
    {"jittered_grid", [] { return gen::Grid(30, 24, 1.2, 1.0, 0.3, 5); }},
    {"sphere", [] { return gen::Sphere(4, 1.0); }},
    {"cube", [] { return gen::Cube(12, 1.0); }},
    {"torus", [] { return gen::Torus(48, 20, 2.0, 0.7); }},
    {"double_torus", [] { return gen::DoubleTorus(6, 4.0); }},
    {"folded_sheet", [] { return gen::FoldedSheet(30, 20, 1.5, 1.0, 1.2); }},
    {"square_with_hole", [] { return gen::SquareWithHole(30, 3.0); }},
    {"grid_with_unreferenced_vertices", GridWithUnreferencedVertices},
    {"two_components", [] { return gen::TwoComponents(10); }},
};

class CgalCrossCheckGeneratedTest : public ::testing::TestWithParam<GeneratedCase> {};

TEST_P(CgalCrossCheckGeneratedTest, AgreesAtEveryVertex) {
  const Mesh m = GetParam().make();
  const int32_t v = ReferencedVertexFrom(m, m.num_vertices() / 3);
  const std::vector<NamedSource> sources = {
      {absl::StrFormat("vertex %d", v), AtVertex(m, v), v},
      {absl::StrFormat("inside face %d", m.num_faces() / 2), InsideFace(m.num_faces() / 2)},
      {"edge midpoint", InteriorEdgeMidpoint(m, m.num_faces() / 5)},
  };
  const Agreement a = CheckAgreement(m, sources);
  Report(GetParam().name, m, sources.size(), a);
}

INSTANTIATE_TEST_SUITE_P(Generated, CgalCrossCheckGeneratedTest,
                         ::testing::ValuesIn(kGeneratedCases),
                         [](const ::testing::TestParamInfo<GeneratedCase>& info) {
                           return info.param.name;
                         });

// ============================================================================
// Development meshes, when present (they are not part of this repository).

std::string SharedMeshDir() {
  if (const char* env = std::getenv("GEODEX_SHARED_MESHES"); env != nullptr && *env != '\0') {
    return env;
  }
  return GEODEX_SHARED_MESHES_DEFAULT;
}

struct SharedMeshFile {
  std::string path;  // empty: no shared meshes
};
void PrintTo(const SharedMeshFile& f, std::ostream* os) {
  *os << (f.path.empty() ? "(none)" : std::filesystem::path(f.path).filename().string());
}

// One parameter per mesh file; a single empty parameter when the directory is
// absent, so that the skip shows up with its reason.
std::vector<SharedMeshFile> SharedMeshFiles() {
  std::vector<SharedMeshFile> files;
  std::error_code error;
  const std::filesystem::path dir = SharedMeshDir();
  if (std::filesystem::is_directory(dir, error)) {
    for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
      const std::string ext = entry.path().extension().string();
      if (ext == ".obj" || ext == ".ply" || ext == ".off") files.push_back({entry.path().string()});
    }
  }
  std::sort(files.begin(), files.end(),
            [](const SharedMeshFile& a, const SharedMeshFile& b) { return a.path < b.path; });
  if (files.empty()) files.push_back({});
  return files;
}

std::string TestNameOf(const std::string& file) {
  if (file.empty()) return "NoSharedMeshes";
  std::string name = std::filesystem::path(file).filename().string();
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

class CgalCrossCheckSharedMeshTest : public ::testing::TestWithParam<SharedMeshFile> {};

TEST_P(CgalCrossCheckSharedMeshTest, AgreesAtEveryVertex) {
  const std::string& file = GetParam().path;
  if (file.empty()) {
    GTEST_SKIP() << "no shared meshes: '" << SharedMeshDir()
                 << "' is not a directory with .obj/.ply/.off files (set GEODEX_SHARED_MESHES)";
  }
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " has gone since test discovery";
  const std::string filename = std::filesystem::path(file).filename().string();
  absl::StatusOr<Mesh> m = mesh::LoadMesh(file);
  if (filename == "cow_nonmanifold_3k.obj") {
    // A negative sample: our loader must refuse it, saying why.
    ASSERT_FALSE(m.ok()) << file << " should be rejected";
    EXPECT_EQ(m.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(m.status().message(), HasSubstr("non-manifold vertex"));
    std::printf("[ cgal     ] %s rejected as expected: %s\n", filename.c_str(),
                std::string(m.status().message()).c_str());
    return;
  }
  ASSERT_TRUE(m.ok()) << m.status();
  if (m->num_vertices() >= kMaxVertices) {
    GTEST_SKIP() << filename << " has " << m->num_vertices() << " vertices (>= " << kMaxVertices
                 << "): CGAL's sequence tree would need several GB (~9 GB on igea_134k)";
  }
  const int32_t v = ReferencedVertexFrom(*m, m->num_vertices() / 3);
  const int32_t f = m->num_faces() / 2;
  const std::vector<NamedSource> sources = {
      {absl::StrFormat("vertex %d", v), AtVertex(*m, v), v},
      {absl::StrFormat("inside face %d", f), InsideFace(f)},
  };
  const Agreement a = CheckAgreement(*m, sources);
  Report(filename, *m, sources.size(), a);
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, CgalCrossCheckSharedMeshTest,
                         ::testing::ValuesIn(SharedMeshFiles()),
                         [](const ::testing::TestParamInfo<SharedMeshFile>& info) {
                           return TestNameOf(info.param.path);
                         });

}  // namespace
}  // namespace geodex
