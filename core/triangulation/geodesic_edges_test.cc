#include "core/triangulation/geodesic_edges.h"

#include <cmath>
#include <optional>

#include "absl/strings/str_cat.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/broken_meshes_testing.h"
#include "core/mesh/generators.h"
#include "core/triangulation/geodesic_triangulation.h"
#include "core/triangulation/shapes_testing.h"
#include "gtest/gtest.h"

namespace geodex::triangulation {
namespace {

namespace gen = mesh::gen;
using mesh::SurfacePoint;

// Vertex (i, j) of gen::Grid(n, n, n, n): unit cells, vertex at (i, j, 0).
int32_t GridVertex(int n, int i, int j) { return j * (n + 1) + i; }

// A hand-made path through the given grid vertices (consecutive ones adjacent).
std::vector<SurfacePoint> VertexPath(const mesh::Mesh& grid, int n,
                                     const std::vector<std::pair<int, int>>& ij) {
  std::vector<SurfacePoint> path;
  for (const auto& [i, j] : ij) path.push_back(*mesh::VertexPoint(grid, GridVertex(n, i, j)));
  return path;
}

// The exact geodesic between two vertices, from the solver.
GeodesicEdge Geodesic(const mesh::Mesh& m, const std::vector<int32_t>& samples, int32_t a,
                      int32_t b) {
  geodesic::ExactGeodesicSolver solver(m);
  EXPECT_TRUE(solver.Propagate({*mesh::VertexPoint(m, samples[a])}).ok());
  GeodesicEdge edge;
  edge.a = a;
  edge.b = b;
  edge.distance = solver.VertexDistance(samples[b]);
  auto path = solver.PathTo(*mesh::VertexPoint(m, samples[b]));
  EXPECT_TRUE(path.ok()) << path.status();
  edge.path.assign(path->rbegin(), path->rend());
  return edge;
}

TEST(GeodesicEdgesTest, DelaunayEdgesAreUniqueSortedPairs) {
  const std::vector<std::array<int32_t, 3>> triangles = {{0, 1, 2}, {2, 1, 3}};
  const auto edges = DelaunayEdges(triangles);
  const std::vector<std::pair<int32_t, int32_t>> expected = {
      {0, 1}, {0, 2}, {1, 2}, {1, 3}, {2, 3}};
  EXPECT_EQ(edges, expected);
}

// On every shape: the repaired triangulation's edges are exact geodesics
// (length = d(a, b) of an independent full propagation), run from sample to
// sample, and do not cross.
TEST(GeodesicEdgesTest, TracedEdgesAreExactAndDoNotCrossOnEveryShape) {
  for (TestShape& shape : TestShapes()) {
    SCOPED_TRACE(shape.name);
    const mesh::Mesh& m = shape.mesh;
    auto set = sampling::FarthestPointSampling(m, shape.samples, 1);
    ASSERT_TRUE(set.ok());
    RepairReport report;
    auto dual = RepairTriangulation(
        m, &*set, {.max_rounds = 200, .max_samples = 2000, .check_edges = true, .threads = 2},
        &report);
    ASSERT_TRUE(dual.ok()) << dual.status();
    const auto& samples = set->samples;
    ASSERT_EQ(dual->edges.size(), DelaunayEdges(dual->triangles).size());
    geodesic::ExactGeodesicSolver solver(m);
    int32_t propagated_from = -1;
    for (const GeodesicEdge& e : dual->edges) {
      ASSERT_LT(e.a, e.b);
      ASSERT_GE(e.path.size(), 2u);
      EXPECT_EQ(mesh::PositionOf(m, e.path.front()), m.position(samples[e.a]));
      EXPECT_EQ(mesh::PositionOf(m, e.path.back()), m.position(samples[e.b]));
      EXPECT_NEAR(e.length, e.distance, 1e-9 * e.distance);
      if (e.a < 6) {  // an independent full propagation for the first samples' edges
        if (propagated_from != e.a) {
          ASSERT_TRUE(solver.Propagate({*mesh::VertexPoint(m, samples[e.a])}).ok());
          propagated_from = e.a;
        }
        EXPECT_NEAR(e.length, solver.VertexDistance(samples[e.b]), 1e-9 * e.length);
      }
      if (std::string(shape.name) == "grid") {  // flat and convex: d = Euclidean distance
        const double euclid = (m.position(samples[e.a]) - m.position(samples[e.b])).norm();
        EXPECT_NEAR(e.length, euclid, 1e-9 * euclid);
      }
    }
    auto crossings = FindCrossings(m, samples, dual->edges);
    ASSERT_TRUE(crossings.ok()) << crossings.status();
    EXPECT_TRUE(crossings->empty());
    const EdgeStats stats = SummarizeEdges(dual->edges);
    EXPECT_EQ(stats.count, static_cast<int32_t>(dual->edges.size()));
    EXPECT_LT(stats.max_relative_error, 1e-9);
    std::printf("%-18s %4zu samples (%s), %d edges, %d crossings found, longest %.4g\n", shape.name,
                samples.size(), report.Summary().c_str(), stats.count, report.crossings_found,
                stats.longest);
  }
}

// The double torus with 80 samples: the dual passes CheckDual, but two pairs
// of geodesic edges overlap where they run through the same saddle vertex.
TEST(GeodesicEdgesTest, CrossingEdgesOfAValidDualAreFoundAndRepaired) {
  const mesh::Mesh m = gen::DoubleTorus(12, 4.0);
  auto set = sampling::FarthestPointSampling(m, 80, 1);
  ASSERT_TRUE(set.ok());
  const DualComplex valid = CheckDual(m, set->nearest, 80);
  ASSERT_TRUE(valid.violations.empty());
  auto edges = TraceEdges(m, set->samples, valid.triangles, 2);
  ASSERT_TRUE(edges.ok()) << edges.status();
  auto crossings = FindCrossings(m, set->samples, *edges);
  ASSERT_TRUE(crossings.ok()) << crossings.status();
  EXPECT_FALSE(crossings->empty());

  // Without the edge check the dual is accepted as it is.
  sampling::SampleSet unchecked = *set;
  RepairReport report;
  auto dual = RepairTriangulation(m, &unchecked, {}, &report);
  ASSERT_TRUE(dual.ok());
  EXPECT_EQ(report.samples_added, 0);
  EXPECT_TRUE(dual->edges.empty());

  // With it, samples are added until no edges cross.
  sampling::SampleSet checked = *set;
  report = {};
  dual = RepairTriangulation(m, &checked, {.check_edges = true, .threads = 2}, &report);
  ASSERT_TRUE(dual.ok()) << dual.status();
  EXPECT_GT(report.added_for[static_cast<int>(ViolationKind::kEdgesCross)], 0);
  EXPECT_GE(report.crossings_found, static_cast<int32_t>(crossings->size()));
  EXPECT_NE(report.Summary().find("for geodesic edges crossing"), std::string::npos);
  EXPECT_TRUE(dual->violations.empty());
  EXPECT_EQ(dual->edges.size(), DelaunayEdges(dual->triangles).size());
  auto after = FindCrossings(m, checked.samples, dual->edges);
  ASSERT_TRUE(after.ok());
  EXPECT_TRUE(after->empty());
  // The same samples whatever the thread count.
  sampling::SampleSet one_thread = *set;
  RepairReport one_report;
  ASSERT_TRUE(
      RepairTriangulation(m, &one_thread, {.check_edges = true, .threads = 1}, &one_report).ok());
  EXPECT_EQ(one_thread.samples, checked.samples);

  // Capped, the crossing is what is left.
  sampling::SampleSet capped = *set;
  report = {};
  dual = RepairTriangulation(m, &capped, {.max_rounds = 0, .check_edges = true}, &report);
  EXPECT_EQ(dual.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(dual.status().message().find("geodesic edges crossing"), std::string::npos);
}

TEST(GeodesicEdgesTest, TracingIsIdenticalForAnyThreadCount) {
  const mesh::Mesh m = gen::Torus(64, 32, 2.0, 0.7);
  auto set = sampling::FarthestPointSampling(m, 60, 1);
  ASSERT_TRUE(set.ok());
  RepairReport report;
  auto dual = RepairTriangulation(m, &*set, {}, &report);
  ASSERT_TRUE(dual.ok());
  auto one = TraceEdges(m, set->samples, dual->triangles, 1);
  auto three = TraceEdges(m, set->samples, dual->triangles, 3);
  ASSERT_TRUE(one.ok() && three.ok());
  ASSERT_EQ(one->size(), three->size());
  for (size_t i = 0; i < one->size(); ++i) {
    const GeodesicEdge &x = (*one)[i], &y = (*three)[i];
    EXPECT_EQ(x.a, y.a);
    EXPECT_EQ(x.b, y.b);
    EXPECT_EQ(x.length, y.length);
    ASSERT_EQ(x.path.size(), y.path.size());
    for (size_t k = 0; k < x.path.size(); ++k) {
      EXPECT_EQ(x.path[k].face, y.path[k].face);
      EXPECT_EQ(x.path[k].w, y.path[k].w);
    }
  }
}

TEST(GeodesicEdgesTest, TraceRejectsBadInput) {
  const mesh::Mesh m = gen::Grid(4, 4, 4.0, 4.0);
  const std::vector<std::array<int32_t, 3>> triangles = {{0, 1, 2}};
  const std::vector<int32_t> out_of_range = {0, 1, 999};
  EXPECT_EQ(TraceEdges(m, out_of_range, triangles).status().code(),
            absl::StatusCode::kInvalidArgument);
  const std::vector<int32_t> two = {0, 1};
  EXPECT_EQ(TraceEdges(m, two, triangles).status().code(), absl::StatusCode::kInvalidArgument);
  // Adjacent samples on different components.
  const mesh::Mesh apart = gen::TwoComponents(4);
  const std::vector<int32_t> split = {0, 1, apart.num_vertices() - 1};
  EXPECT_EQ(TraceEdges(apart, split, triangles).status().code(), absl::StatusCode::kNotFound);
}

// Hand-made configurations on a flat 8 x 8 grid of unit cells.
class CrossingTest : public ::testing::Test {
 protected:
  static constexpr int kN = 8;
  const mesh::Mesh grid_ = gen::Grid(kN, kN, kN, kN);

  int32_t V(int i, int j) const { return GridVertex(kN, i, j); }
  absl::StatusOr<std::vector<EdgeCrossing>> Find(const std::vector<int32_t>& samples,
                                                 const std::vector<GeodesicEdge>& edges) const {
    return FindCrossings(grid_, samples, edges);
  }
};

TEST_F(CrossingTest, ProperCrossingInsideAFace) {
  // (0,0)-(4,3) and (0,2)-(3,0) cross at (24/17, 18/17), inside a face.
  const std::vector<int32_t> samples = {V(0, 0), V(4, 3), V(0, 2), V(3, 0)};
  const std::vector<GeodesicEdge> edges = {Geodesic(grid_, samples, 0, 1),
                                           Geodesic(grid_, samples, 2, 3)};
  auto found = Find(samples, edges);
  ASSERT_TRUE(found.ok()) << found.status();
  ASSERT_EQ(found->size(), 1u);
  EXPECT_EQ((*found)[0].first, 0);
  EXPECT_EQ((*found)[0].second, 1);
  const mesh::Vec3 at = mesh::PositionOf(grid_, (*found)[0].point);
  EXPECT_NEAR(at.x(), 24.0 / 17, 1e-9);
  EXPECT_NEAR(at.y(), 18.0 / 17, 1e-9);
}

TEST_F(CrossingTest, CrossingExactlyOnAMeshEdge) {
  // (0,1)-(4,2) and (0,2)-(4,1) cross at (2, 1.5), on the mesh edge x = 2.
  const std::vector<int32_t> samples = {V(0, 1), V(4, 2), V(0, 2), V(4, 1)};
  const std::vector<GeodesicEdge> edges = {Geodesic(grid_, samples, 0, 1),
                                           Geodesic(grid_, samples, 2, 3)};
  auto found = Find(samples, edges);
  ASSERT_TRUE(found.ok()) << found.status();
  ASSERT_EQ(found->size(), 1u);
  const mesh::Vec3 at = mesh::PositionOf(grid_, (*found)[0].point);
  EXPECT_NEAR(at.x(), 2.0, 1e-9);
  EXPECT_NEAR(at.y(), 1.5, 1e-9);
}

TEST_F(CrossingTest, PathsThroughTheSameMeshVertexTouch) {
  // Both pass through the non-sample vertex (2,2), one coming from the left
  // and leaving downwards, the other from the right and upwards: they touch
  // without crossing, and share no face there.
  const std::vector<int32_t> samples = {V(0, 2), V(2, 0), V(4, 2), V(2, 4)};
  std::vector<GeodesicEdge> edges(2);
  edges[0] = {0, 1, 0, 0, VertexPath(grid_, kN, {{0, 2}, {1, 2}, {2, 2}, {2, 1}, {2, 0}})};
  edges[1] = {2, 3, 0, 0, VertexPath(grid_, kN, {{4, 2}, {3, 2}, {2, 2}, {2, 3}, {2, 4}})};
  auto found = Find(samples, edges);
  ASSERT_TRUE(found.ok()) << found.status();
  ASSERT_EQ(found->size(), 1u);
  EXPECT_LT((mesh::PositionOf(grid_, (*found)[0].point) - mesh::Vec3(2, 2, 0)).norm(), 1e-9);
}

TEST_F(CrossingTest, TTouchAtTheSampleOfAnotherEdge) {
  // (0,2)-(4,2) runs through (2,2), where (2,0)-(2,2) ends.
  const std::vector<int32_t> samples = {V(0, 2), V(4, 2), V(2, 0), V(2, 2)};
  const std::vector<GeodesicEdge> edges = {Geodesic(grid_, samples, 0, 1),
                                           Geodesic(grid_, samples, 2, 3)};
  auto found = Find(samples, edges);
  ASSERT_TRUE(found.ok()) << found.status();
  EXPECT_EQ(found->size(), 1u);
}

TEST_F(CrossingTest, EdgesSharingASampleDoNotCountThere) {
  // A fan of edges from (0,0), some along mesh edges, one along a diagonal,
  // and a triangle around it: no crossing.
  const std::vector<int32_t> samples = {V(0, 0), V(4, 3), V(3, 4), V(5, 0), V(0, 5)};
  std::vector<GeodesicEdge> edges;
  for (const auto& [a, b] :
       std::vector<std::pair<int, int>>{{0, 1}, {0, 2}, {0, 3}, {0, 4}, {1, 2}, {1, 3}, {2, 4}}) {
    edges.push_back(Geodesic(grid_, samples, a, b));
  }
  auto found = Find(samples, edges);
  ASSERT_TRUE(found.ok()) << found.status();
  EXPECT_TRUE(found->empty());
  // But two edges leaving their common sample in the same direction overlap:
  // (0,0)-(2,2) lies on (0,0)-(4,4).
  const std::vector<int32_t> collinear = {V(0, 0), V(4, 4), V(2, 2)};
  const std::vector<GeodesicEdge> overlap = {Geodesic(grid_, collinear, 0, 1),
                                             Geodesic(grid_, collinear, 0, 2)};
  found = Find(collinear, overlap);
  ASSERT_TRUE(found.ok()) << found.status();
  EXPECT_EQ(found->size(), 1u);
}

TEST_F(CrossingTest, NearMissIsNotATouch) {
  // Parallel paths half a cell apart, and a path stopping short of another.
  const std::vector<int32_t> samples = {V(0, 1), V(6, 4), V(0, 2), V(6, 5), V(7, 0), V(7, 6)};
  const std::vector<GeodesicEdge> edges = {Geodesic(grid_, samples, 0, 1),
                                           Geodesic(grid_, samples, 2, 3),
                                           Geodesic(grid_, samples, 4, 5)};
  auto found = Find(samples, edges);
  ASSERT_TRUE(found.ok()) << found.status();
  EXPECT_TRUE(found->empty());
}

TEST_F(CrossingTest, RejectsPathsThatJump) {
  const std::vector<int32_t> samples = {V(0, 0), V(4, 0)};
  std::vector<GeodesicEdge> edges(1);
  edges[0] = {0, 1, 4, 4, VertexPath(grid_, kN, {{0, 0}, {4, 0}})};
  EXPECT_EQ(Find(samples, edges).status().code(), absl::StatusCode::kInvalidArgument);
}

// A 4 x 4 grid of unit cells with a zero-area cap: an inner face (a, c, d)
// split at the midpoint b of its side (a, c) into (a, b, d) and (b, c, d),
// with the zero-area face (a, c, b) between them and the face (c, a, e)
// across the side, as scans and their repair leave them.
class ZeroAreaCapTest : public ::testing::Test {
 protected:
  void SetUp() override {
    mesh::RawMesh raw = mesh::testing::RawOf(gen::Grid(4, 4, 4.0, 4.0), "grid");
    const mesh::Mesh grid = gen::Grid(4, 4, 4.0, 4.0);
    // An inner face whose first side has a face on its other side.
    int32_t face = 0;
    while (grid.Twin(3 * face) == mesh::kNone) ++face;
    a_ = raw.triangles[face][0];
    c_ = raw.triangles[face][1];
    d_ = raw.triangles[face][2];
    const int32_t twin = grid.Twin(3 * face);
    e_ = grid.face(mesh::Mesh::FaceOf(twin))[(twin % 3 + 2) % 3];
    split_ = face;
    cap_ = mesh::testing::AddZeroAreaFace(&raw, face);
    b_ = static_cast<int32_t>(raw.positions.size()) - 1;
    auto m = mesh::Mesh::Create(raw.positions, raw.triangles, "capped grid",
                                {.allow_zero_area_faces = true});
    ASSERT_TRUE(m.ok()) << m.status();
    mesh_.emplace(*std::move(m));
  }

  std::optional<mesh::Mesh> mesh_;
  int32_t a_ = 0, b_ = 0, c_ = 0, d_ = 0, e_ = 0, split_ = 0, cap_ = 0;
};

// In the cap, b lies on the side (a, c) in space: flattened, every piece in
// it would touch every other. It is told apart by its corners: the path along
// the side meets neither b nor the paths leaving b away from the side, but a
// path from b across the side into the face beyond crosses it.
TEST_F(ZeroAreaCapTest, CrossingsInTheCapGoByItsCorners) {
  const std::vector<int32_t> samples = {a_, c_, b_, d_, e_};
  auto at = [](int32_t face, double wa, double wb, double wc) {
    return SurfacePoint{face, {wa, wb, wc}};
  };
  // The cap is (a, c, b), the split face (a, b, d).
  const GeodesicEdge side = {0, 1, 1, 1, {at(cap_, 1, 0, 0), at(cap_, 0, 1, 0)}};
  const GeodesicEdge to_a = {0, 2, 0.5, 0.5, {at(cap_, 1, 0, 0), at(cap_, 0, 0, 1)}};
  const GeodesicEdge to_c = {1, 2, 0.5, 0.5, {at(cap_, 0, 1, 0), at(cap_, 0, 0, 1)}};
  const GeodesicEdge away = {2, 3, 1, 1, {at(split_, 0, 1, 0), at(split_, 0, 0, 1)}};
  auto found = FindCrossings(*mesh_, samples, std::vector<GeodesicEdge>{side, to_a, to_c, away});
  ASSERT_TRUE(found.ok()) << found.status();
  EXPECT_TRUE(found->empty()) << "edges " << (*found)[0].first << ", " << (*found)[0].second;
  const GeodesicEdge across = {
      2, 4, 1, 1, {at(cap_, 0, 0, 1), at(cap_, 0.5, 0.5, 0), *mesh::VertexPoint(*mesh_, e_)}};
  found = FindCrossings(*mesh_, samples, std::vector<GeodesicEdge>{side, across});
  ASSERT_TRUE(found.ok()) << found.status();
  EXPECT_EQ(found->size(), 1u);
}

// Samples joined by a mesh edge as long as their distance are joined by that
// edge: a and c not through the cap's apex b, as the propagation's path
// between them goes, at zero extra length. The triangles round b then embed.
TEST_F(ZeroAreaCapTest, AdjacentSamplesAreJoinedByTheirMeshEdge) {
  const std::vector<int32_t> samples = {a_, c_, b_, d_, e_};
  const std::vector<std::array<int32_t, 3>> triangles = {
      {0, 1, 2}, {0, 2, 3}, {2, 1, 3}, {1, 0, 4}};
  auto edges = TraceEdges(*mesh_, samples, triangles);
  ASSERT_TRUE(edges.ok()) << edges.status();
  for (const GeodesicEdge& edge : *edges) {
    SCOPED_TRACE(absl::StrCat(edge.a, "-", edge.b));
    EXPECT_EQ(edge.path.size(), 2u);
    EXPECT_NEAR(edge.length, edge.distance, 1e-12);
    EXPECT_EQ(mesh::PositionOf(*mesh_, edge.path.front()), mesh_->position(samples[edge.a]));
    EXPECT_EQ(mesh::PositionOf(*mesh_, edge.path.back()), mesh_->position(samples[edge.b]));
  }
  auto found = FindCrossings(*mesh_, samples, *edges);
  ASSERT_TRUE(found.ok()) << found.status();
  EXPECT_TRUE(found->empty());
}

TEST(GeodesicEdgesTest, ObjHasAVertexPerPointAndALinePerEdge) {
  const mesh::Mesh m = gen::Grid(4, 4, 4.0, 4.0);
  const std::vector<int32_t> samples = {0, 24, 4};
  const std::vector<GeodesicEdge> edges = {Geodesic(m, samples, 0, 1), Geodesic(m, samples, 0, 2)};
  const std::string obj = EdgesToObj(m, edges);
  size_t v = 0, l = 0, points = 0;
  for (const auto& e : edges) points += e.path.size();
  for (size_t pos = 0; pos < obj.size();) {
    const size_t end = obj.find('\n', pos);
    v += obj.compare(pos, 2, "v ") == 0;
    l += obj.compare(pos, 2, "l ") == 0;
    pos = end + 1;
  }
  EXPECT_EQ(v, points);
  EXPECT_EQ(l, 2u);
}

}  // namespace
}  // namespace geodex::triangulation
