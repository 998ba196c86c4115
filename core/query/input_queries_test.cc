// Queries over indexes of repaired meshes, in the input's ids: a generated
// broken mesh of each kind is repaired, built and answered.

#include "core/query/input_queries.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "absl/strings/str_format.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/index/index.h"
#include "core/mesh/broken_meshes_testing.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_repair.h"
#include "core/query/engine/input_ids.h"
#include "core/query/engine/query_engine.h"
#include "core/build/build_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

using mesh::RawMesh;
using mesh::RepairedMesh;
using mesh::SurfacePoint;
using mesh::testing::AddTriangle;
using mesh::testing::RawOf;

using Built = geodex::testing::RepairedTestEngine;

// Repairs, builds (as geodex-build does, with the long-edge split when
// `refine`) and loads an index of `raw`.
Built Build(const RawMesh& raw, int32_t samples, bool refine = false) {
  return geodex::testing::RepairedTestEngineOrThrow(raw, samples, refine);
}

double InputDistance(const QueryEngine& engine, const SurfacePoint& a, const SurfacePoint& b,
                     NearPairs near = NearPairs::kPath) {
  absl::StatusOr<SurfacePoint> p = InputIds(engine.index()).ToInternal(a);
  absl::StatusOr<SurfacePoint> q = InputIds(engine.index()).ToInternal(b);
  if (!p.ok() || !q.ok()) throw std::runtime_error("bad point");
  DistanceOptions options;
  options.near_pairs = near;
  absl::StatusOr<double> d = engine.Distance(*p, *q, options);
  if (!d.ok()) throw std::runtime_error(d.status().ToString());
  return *d;
}

TEST(InputIdsTest, IndexWithoutRepairHasIdentityMaps) {
  Built b = Build(RawOf(mesh::gen::Sphere(2, 1.0), "sphere"), 40);
  const InputIds ids(b.engine->index());
  EXPECT_TRUE(ids.identity());
  EXPECT_TRUE(b.engine->index().input_faces().empty());
  EXPECT_EQ(ids.num_input_faces(), 320);
  const SurfacePoint p{17, {0.2, 0.3, 0.5}};
  absl::StatusOr<SurfacePoint> q = ids.ToInternal(p);
  ASSERT_TRUE(q.ok());
  EXPECT_EQ(q->face, 17);
  EXPECT_EQ(ids.ToInput(p).w, p.w);
  EXPECT_EQ(ids.ToInternal({320, {1, 0, 0}}).status().code(), absl::StatusCode::kOutOfRange);
}

TEST(InputIdsTest, DroppedDuplicateAnswersAsItsTwin) {
  const mesh::Mesh sphere = mesh::gen::Sphere(2, 1.0);
  RawMesh raw = RawOf(sphere, "sphere");
  const mesh::Triangle t = raw.triangles[7];
  AddTriangle(&raw, {t[1], t[2], t[0]});  // input face 320
  AddTriangle(&raw, {t[0], t[2], t[1]});  // input face 321
  Built b = Build(raw, 40);
  const QueryEngine& e = *b.engine;
  // The input's face count, so face 321 is valid and 322 is not.
  EXPECT_EQ(InputIds(e.index()).num_input_faces(), 322);
  EXPECT_EQ(e.index().num_faces(), 320);
  EXPECT_EQ(InputIds(e.index()).ToInternal({322, {1, 0, 0}}).status().code(),
            absl::StatusCode::kOutOfRange);
  const SurfacePoint far{150, {0.3, 0.3, 0.4}};
  // The same point of space: weights follow each description's corners.
  const SurfacePoint on_twin{7, {0.2, 0.3, 0.5}};
  const SurfacePoint on_rotated{320, {0.3, 0.5, 0.2}};
  const SurfacePoint on_reversed{321, {0.2, 0.5, 0.3}};
  const double d = InputDistance(e, on_twin, far);
  EXPECT_GT(d, 0);
  EXPECT_EQ(InputDistance(e, on_rotated, far), d);
  EXPECT_EQ(InputDistance(e, on_reversed, far), d);
  // Answers name the kept face.
  absl::StatusOr<SurfacePoint> internal = InputIds(e.index()).ToInternal(on_reversed);
  ASSERT_TRUE(internal.ok());
  const SurfacePoint back = InputIds(e.index()).ToInput(*internal);
  EXPECT_EQ(back.face, 7);
  EXPECT_EQ(back.w, on_twin.w);
}

TEST(InputIdsTest, ReorientedFacesKeepTheirInputWeights) {
  const mesh::Mesh sphere = mesh::gen::Sphere(2, 1.0);
  RawMesh raw = RawOf(sphere, "sphere");
  for (int32_t f : {0, 5, 17, 200}) std::swap(raw.triangles[f][1], raw.triangles[f][2]);
  Built b = Build(raw, 40);
  const QueryEngine& e = *b.engine;
  // Input face 5 is (a, c, b) of the sphere's (a, b, c): weights (x, y, z) on
  // it are (x, z, y) on the sphere's face 5.
  const SurfacePoint far{150, {0.3, 0.3, 0.4}};
  Built reference = Build(RawOf(sphere, "sphere"), 40);
  EXPECT_EQ(InputDistance(e, {5, {0.1, 0.2, 0.7}}, far),
            InputDistance(*reference.engine, {5, {0.1, 0.7, 0.2}}, far));
  // A path from a re-oriented face starts there, in its input weights.
  absl::StatusOr<SurfacePoint> from = InputIds(e.index()).ToInternal({5, {0.1, 0.2, 0.7}});
  absl::StatusOr<SurfacePoint> to = InputIds(e.index()).ToInternal(far);
  ASSERT_TRUE(from.ok() && to.ok());
  absl::StatusOr<std::vector<PathPoint>> path = e.Path(*from, *to);
  ASSERT_TRUE(path.ok()) << path.status();
  InputIds(e.index()).PathToInput(*path);
  EXPECT_EQ(path->front().point.face, 5);
  EXPECT_NEAR(path->front().point.w[1], 0.2, 1e-12);
  EXPECT_NEAR(path->front().point.w[2], 0.7, 1e-12);
  EXPECT_EQ(path->back().point.face, 150);
}

TEST(InputIdsTest, SplitVertexFieldTakesTheSmallestCopy) {
  const RawMesh raw = mesh::testing::TwoPyramidsApexToApex();
  Built b = Build(raw, 10);
  const QueryEngine& e = *b.engine;
  ASSERT_EQ(e.index().vertex_copies().size(), 1u);
  EXPECT_EQ(InputIds(e.index()).num_input_vertices(), 9);
  // A source on the first pyramid: its copy of the apex is reached, the
  // other pyramid is another component.
  absl::StatusOr<SurfacePoint> source = InputIds(e.index()).ToInternal({0, {0.2, 0.3, 0.5}});
  ASSERT_TRUE(source.ok());
  absl::StatusOr<DistanceField> field = e.Field(std::vector<SurfacePoint>{*source});
  ASSERT_TRUE(field.ok());
  ASSERT_EQ(field->distance.size(), 10u);
  const double apex_copy = field->distance[9];
  const DistanceField input = InputIds(e.index()).FieldToInput(*field);
  ASSERT_EQ(input.distance.size(), 9u);
  EXPECT_EQ(input.distance[0], std::min(field->distance[0], apex_copy));
  EXPECT_TRUE(std::isfinite(input.distance[0]));
  EXPECT_EQ(InputIds(e.index()).InputVertex(9), 0);
}

TEST(InputIdsTest, CubesSharingAnEdgeBuildAndAnswer) {
  Built b = Build(mesh::testing::TwoCubesSharingAnEdge(), 16);
  const QueryEngine& e = *b.engine;
  // Across one face of the first cube: a straight line.
  const double d = InputDistance(e, {0, {1.0 / 3, 1.0 / 3, 1.0 / 3}},
                                 {1, {1.0 / 3, 1.0 / 3, 1.0 / 3}}, NearPairs::kExact);
  EXPECT_TRUE(std::isfinite(d));
  // The two cubes are separate surfaces once the edge is cut.
  EXPECT_EQ(InputDistance(e, {0, {1, 0, 0}}, {12, {0.2, 0.3, 0.5}}),
            std::numeric_limits<double>::infinity());
}

TEST(InputIdsTest, ZeroAreaFaceBuildsAndAnswersFiniteDistances) {
  RawMesh raw = RawOf(mesh::gen::Grid(8, 8, 1, 1), "grid");
  const int32_t degenerate = mesh::testing::AddZeroAreaFace(&raw, 60);
  Built b = Build(raw, 30);
  const QueryEngine& e = *b.engine;
  ASSERT_EQ(b.repaired.report.zero_area_faces, 1);
  // Points on the zero-area face, and across it: the grid is flat and
  // convex, so distances are Euclidean.
  const std::vector<SurfacePoint> points = {
      {degenerate, {0.2, 0.3, 0.5}}, {degenerate, {1, 0, 0}},  {60, {0.3, 0.3, 0.4}},
      {0, {0.2, 0.2, 0.6}},          {127, {0.5, 0.25, 0.25}}, {degenerate - 1, {0.6, 0.2, 0.2}}};
  const mesh::Mesh& m = b.repaired.mesh;
  for (const SurfacePoint& p : points) {
    for (const SurfacePoint& q : points) {
      for (NearPairs near : {NearPairs::kPath, NearPairs::kUnfold, NearPairs::kExact}) {
        const double d = InputDistance(e, p, q, near);
        const double euclid = (mesh::PositionOf(m, p) - mesh::PositionOf(m, q)).norm();
        EXPECT_TRUE(std::isfinite(d)) << p.face << " " << q.face;
        EXPECT_NEAR(d, euclid, 0.05) << p.face << " " << q.face << " mode " << int(near);
      }
      absl::StatusOr<std::vector<PathPoint>> path = e.Path(p, q);
      ASSERT_TRUE(path.ok()) << path.status();
      for (const PathPoint& x : *path) EXPECT_TRUE(x.position.allFinite());
    }
  }
  absl::StatusOr<DistanceField> field = e.Field(std::vector<SurfacePoint>{points[0]});
  ASSERT_TRUE(field.ok());
  for (double d : field->distance) EXPECT_TRUE(std::isfinite(d));
  absl::StatusOr<LocatedPoint> located = e.Locate(mesh::PositionOf(m, points[0]));
  ASSERT_TRUE(located.ok());
  EXPECT_NEAR(located->distance, 0, 1e-12);
}

// The development meshes, when present: cow_nonmanifold_3k (one non-manifold
// vertex) builds once repaired and answers.
TEST(InputIdsTest, CowNonmanifoldBuildsAndAnswers) {
  const char* env = std::getenv("GEODEX_SHARED_MESHES");
  const std::string dir = env != nullptr && *env != '\0'
                              ? std::string(env)
                              : std::string(GEODEX_SOURCE_DIR) + "/../shared/meshes";
  const std::string path = dir + "/cow_nonmanifold_3k.obj";
  if (!std::filesystem::exists(path)) {
    GTEST_SKIP() << "no " << path
                 << " (set GEODEX_SHARED_MESHES, or place the meshes in <source>/../shared/meshes)";
  }
  absl::StatusOr<RawMesh> raw = mesh::LoadRawMeshFile(path);
  ASSERT_TRUE(raw.ok()) << raw.status();
  Built b = Build(*raw, 100);
  EXPECT_EQ(b.repaired.report.nonmanifold_vertices, 1);
  EXPECT_THAT(std::string(b.engine->index().report()),
              ::testing::HasSubstr("mesh_repairs = 1 non-manifold vertex split (2 copies)"));
  const double d = InputDistance(*b.engine, {0, {0.2, 0.3, 0.5}}, {1000, {0.3, 0.3, 0.4}});
  EXPECT_TRUE(std::isfinite(d));
  EXPECT_GT(d, 0);
  mesh::RepairOptions strict;
  strict.strict = true;
  const absl::StatusOr<RepairedMesh> refused = mesh::RepairMesh(*raw, strict);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(refused.status().message(), ::testing::HasSubstr("non-manifold vertex"));
}

// The point of space a surface point of `faces`/`positions` names.
mesh::Vec3 PointOf(std::span<const double> positions, const mesh::Triangle& t,
                   const SurfacePoint& p) {
  mesh::Vec3 x(0, 0, 0);
  for (int i = 0; i < 3; ++i) {
    x += p.w[i] * mesh::Vec3(positions[3 * t[i]], positions[3 * t[i] + 1], positions[3 * t[i] + 2]);
  }
  return x;
}

// Points of each of the 80 input faces of `coarse` (in `points`): the same
// point of space in the internal ids, and back to the same input
// description.
void ExpectSamePointsInBothIds(const QueryEngine& e, const InputIds& ids, const mesh::Mesh& coarse,
                               std::vector<SurfacePoint>* points) {
  const std::span<const double> x = e.index().positions();
  const std::span<const int32_t> faces = e.index().faces();
  auto internal_face = [&](int32_t f) {
    return mesh::Triangle{faces[3 * f], faces[3 * f + 1], faces[3 * f + 2]};
  };
  for (int32_t f = 0; f < 80; ++f) {
    EXPECT_EQ(ids.InputFace(f), coarse.face(f));
    for (const mesh::Vec3& w : {mesh::Vec3(0.2, 0.3, 0.5), mesh::Vec3(1, 0, 0),
                                mesh::Vec3(0.5, 0.5, 0), mesh::Vec3(0.05, 0.05, 0.9)}) {
      const SurfacePoint p{f, {w.x(), w.y(), w.z()}};
      absl::StatusOr<SurfacePoint> in = ids.ToInternal(p);
      ASSERT_TRUE(in.ok()) << in.status();
      // The same point of space, and back to the same input description.
      EXPECT_LT((PointOf(x, internal_face(in->face), *in) - PointOf(x, coarse.face(f), p)).norm(),
                1e-9);
      const SurfacePoint back = ids.ToInput(*in);
      EXPECT_EQ(back.face, f);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(back.w[i], p.w[i], 1e-6);
      points->push_back(p);
    }
  }
}

// The surface is the same: exact distances from an input point, on the
// refined mesh, equal those on the coarse one at every input vertex; the
// O(1) answers are close to them.
void ExpectTheSameSurface(const QueryEngine& e, const InputIds& ids, const mesh::Mesh& coarse,
                          const std::vector<SurfacePoint>& points) {
  geodesic::ExactGeodesicSolver exact(coarse);
  QueryScratch scratch;
  int checked = 0;
  for (size_t i = 0; i < points.size(); i += 37) {
    ASSERT_TRUE(exact.Propagate({points[i]}).ok());
    absl::StatusOr<SurfacePoint> internal = ids.ToInternal(points[i]);
    ASSERT_TRUE(internal.ok());
    absl::StatusOr<std::span<const double>> local = e.LocalExactDistances(*internal, 10, scratch);
    ASSERT_TRUE(local.ok()) << local.status();
    for (int32_t v = 0; v < 42; ++v) EXPECT_NEAR((*local)[v], exact.VertexDistance(v), 1e-9);
    for (size_t j = 5; j < points.size(); j += 23) {
      const double truth = exact.DistanceAt(points[j]);
      if (truth < 0.3) continue;
      EXPECT_NEAR(InputDistance(e, points[i], points[j], NearPairs::kUnfold), truth, 0.06 * truth)
          << i << " " << j;
      ++checked;
    }
  }
  EXPECT_GT(checked, 20);
}

// A coarse sphere (42 vertices, edges about 0.6) sampled more finely than it
// has vertices: only the long-edge split makes room for the samples, and
// every answer still speaks of the input's faces and vertices.
TEST(InputIdsTest, SplitIndexAnswersInTheInputIds) {
  const mesh::Mesh coarse = mesh::gen::Sphere(1, 1.0);
  ASSERT_EQ(coarse.num_vertices(), 42);
  Built b = Build(RawOf(coarse, "sphere"), 120, /*refine=*/true);
  const QueryEngine& e = *b.engine;
  const InputIds ids(e.index());
  EXPECT_GE(e.index().header().format_major, index::kSplitFormatMajor);
  EXPECT_GT(e.index().split_vertices(), 0);
  EXPECT_GE(e.index().num_samples(), 120);
  EXPECT_TRUE(ids.split());
  EXPECT_FALSE(ids.identity());
  EXPECT_EQ(ids.num_input_faces(), 80);
  EXPECT_EQ(ids.num_input_vertices(), 42);
  EXPECT_EQ(ids.ToInternal({80, {1, 0, 0}}).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(std::string(e.index().report()), ::testing::HasSubstr("mesh_split = "));

  const std::span<const double> x = e.index().positions();
  std::vector<SurfacePoint> points;
  ASSERT_NO_FATAL_FAILURE(ExpectSamePointsInBothIds(e, ids, coarse, &points));
  ASSERT_NO_FATAL_FAILURE(ExpectTheSameSurface(e, ids, coarse, points));
  geodesic::ExactGeodesicSolver exact(coarse);
  // Per-vertex answers cover the input's vertices only; midpoints have no
  // input vertex.
  EXPECT_EQ(ids.InputVertex(41), 41);
  EXPECT_EQ(ids.InputVertex(42), mesh::kNone);
  absl::StatusOr<SurfacePoint> source = ids.ToInternal(points[3]);
  ASSERT_TRUE(source.ok());
  absl::StatusOr<DistanceField> field = e.Field(std::vector<SurfacePoint>{*source});
  ASSERT_TRUE(field.ok());
  EXPECT_EQ(field->distance.size(), static_cast<size_t>(e.index().num_vertices()));
  const DistanceField input = ids.FieldToInput(*field);
  ASSERT_EQ(input.distance.size(), 42u);
  ASSERT_TRUE(exact.Propagate({points[3]}).ok());
  for (int32_t v = 0; v < 42; ++v) {
    EXPECT_NEAR(input.distance[v], exact.VertexDistance(v), 0.03 * exact.VertexDistance(v) + 0.02);
  }
  // A path comes back in input faces, from the first point to the second.
  absl::StatusOr<SurfacePoint> to = ids.ToInternal(points[200]);
  ASSERT_TRUE(to.ok());
  absl::StatusOr<std::vector<PathPoint>> path = e.Path(*source, *to);
  ASSERT_TRUE(path.ok()) << path.status();
  ids.PathToInput(*path);
  for (const PathPoint& p : *path) EXPECT_LT(p.point.face, 80);
  EXPECT_LT((PointOf(x, coarse.face(path->front().point.face), path->front().point) -
             PointOf(x, coarse.face(points[3].face), points[3]))
                .norm(),
            1e-9);
}

// Repair and refinement compose: a re-oriented, duplicated coarse mesh.
TEST(InputIdsTest, RepairedAndSplitIndexAnswersInTheInputIds) {
  const mesh::Mesh coarse = mesh::gen::Sphere(1, 1.0);
  RawMesh raw = RawOf(coarse, "sphere");
  for (int32_t f : {0, 5, 17}) std::swap(raw.triangles[f][1], raw.triangles[f][2]);
  const mesh::Triangle t = raw.triangles[7];
  AddTriangle(&raw, {t[1], t[2], t[0]});  // input face 80, a duplicate of 7
  Built b = Build(raw, 120, /*refine=*/true);
  Built reference = Build(RawOf(coarse, "sphere"), 120, /*refine=*/true);
  const InputIds ids(b.engine->index());
  EXPECT_TRUE(ids.split());
  EXPECT_EQ(ids.num_input_faces(), 81);
  EXPECT_EQ(ids.num_input_vertices(), 42);
  const SurfacePoint far{40, {0.3, 0.3, 0.4}};
  // Re-oriented face 5: (x, y, z) on the input is (x, z, y) on the sphere.
  EXPECT_NEAR(InputDistance(*b.engine, {5, {0.1, 0.2, 0.7}}, far, NearPairs::kUnfold),
              InputDistance(*reference.engine, {5, {0.1, 0.7, 0.2}}, far, NearPairs::kUnfold),
              1e-9);
  // The duplicate answers as its twin, and goes back to it.
  const SurfacePoint on_twin{7, {0.2, 0.3, 0.5}};
  const SurfacePoint on_rotated{80, {0.3, 0.5, 0.2}};
  EXPECT_EQ(InputDistance(*b.engine, on_rotated, far), InputDistance(*b.engine, on_twin, far));
  absl::StatusOr<SurfacePoint> internal = ids.ToInternal(on_rotated);
  ASSERT_TRUE(internal.ok());
  const SurfacePoint back = ids.ToInput(*internal);
  EXPECT_EQ(back.face, 7);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(back.w[i], on_twin.w[i], 1e-6);
  EXPECT_EQ(ids.InputFace(5),
            (mesh::Triangle{coarse.face(5)[0], coarse.face(5)[2], coarse.face(5)[1]}));
}

// Points are checked once, where they enter: every error of a bad point
// comes from Read, named by the caller, and the queries after it take the
// read points as they are.
TEST(InputQueriesTest, PointsAreCheckedWhereTheyEnter) {
  const mesh::Mesh sphere = mesh::gen::Sphere(2, 1.0);
  Built b = Build(RawOf(sphere, "sphere"), 40);
  auto queries = InputQueries::Create(b.engine);
  ASSERT_TRUE(queries.ok()) << queries.status();
  const int32_t faces = (*queries)->num_faces();
  std::vector<SurfacePoint> points(50, SurfacePoint{3, {0.2, 0.3, 0.5}});
  EnginePoints read;
  points[42] = {faces, {1, 0, 0}};
  absl::Status status = (*queries)->Read(points, Named("b"), &read);
  EXPECT_EQ(status.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(std::string(status.message()), ::testing::StartsWith("b[42]: face id"));
  points[42] = {0, {NAN, 0.5, 0.5}};
  EXPECT_EQ((*queries)->Read(points, Named("b"), &read).code(), absl::StatusCode::kInvalidArgument);
  points[42] = {0, {-0.5, 1.0, 0.5}};
  EXPECT_THAT((*queries)->Read(points, Named("b"), &read).message(),
              ::testing::HasSubstr("negative"));
  points[42] = {0, {0.5, 0.5, 0.5}};
  EXPECT_THAT((*queries)->Read(points, Named("b"), &read).message(), ::testing::HasSubstr("sum"));
  points[42] = {-1, {1, 0, 0}};
  EXPECT_EQ((*queries)->Read(points, Named("b"), &read).code(), absl::StatusCode::kOutOfRange);
  const std::vector<int32_t> face_ids = {0, 1};
  const std::vector<double> weights = {1, 0, 0};
  EXPECT_EQ((*queries)->Read(face_ids, weights, Named("c"), &read).code(),
            absl::StatusCode::kInvalidArgument);

  EnginePoints none;
  EXPECT_EQ((*queries)->Field(none).status().code(), absl::StatusCode::kInvalidArgument);
}

// Vertex ids as points: weight 1 on the vertex in the lowest face holding
// it (after a face the repair dropped), the same answers as the vertex named
// in any other face, mixed with face points, and refused with the point's
// name when out of range or on no face.
TEST(InputQueriesTest, VertexIdsReadAsTheVertexInItsLowestFace) {
  const mesh::Mesh sphere = mesh::gen::Sphere(2, 1.0);
  RawMesh raw = RawOf(sphere, "sphere");
  // A duplicate of face 7 in front: input face 0, which the repair drops.
  const mesh::Triangle dup = raw.triangles[7];
  raw.triangles.insert(raw.triangles.begin(), dup);
  raw.input_face.insert(raw.input_face.begin(), 0);
  for (size_t t = 1; t < raw.input_face.size(); ++t) raw.input_face[t] = static_cast<int32_t>(t);
  const int32_t lonely = mesh::testing::AddVertex(&raw, mesh::Vec3(0, 0, 3));
  Built b = Build(raw, 40);
  auto queries = InputQueries::Create(b.engine);
  ASSERT_TRUE(queries.ok()) << queries.status();
  const InputQueries& q = **queries;
  ASSERT_EQ(q.num_vertices(), sphere.num_vertices() + 1);

  EnginePoints any_face, by_id;
  std::vector<SurfacePoint> named;
  std::vector<int32_t> ids;
  for (int32_t v = 0; v < sphere.num_vertices(); ++v) {
    absl::StatusOr<SurfacePoint> p = q.VertexPoint(v);
    ASSERT_TRUE(p.ok()) << p.status();
    int32_t lowest = -1, highest = -1;
    for (int32_t f = 0; f < q.num_faces(); ++f) {
      const mesh::Triangle t = q.InputFace(f);
      if (t[0] != v && t[1] != v && t[2] != v) continue;
      if (lowest < 0) lowest = f;
      highest = f;
    }
    // The lowest face but the dropped one, which reads as its twin.
    EXPECT_TRUE(p->face == lowest || (lowest == 0 && p->face > 0)) << "vertex " << v;
    const mesh::Triangle t = q.InputFace(p->face);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(p->w[k], t[k] == v ? 1.0 : 0.0) << "vertex " << v;
    SurfacePoint other{highest, {0, 0, 0}};
    const mesh::Triangle h = q.InputFace(highest);
    for (int k = 0; k < 3; ++k) other.w[k] = h[k] == v ? 1.0 : 0.0;
    named.push_back(other);
    ids.push_back(v);
  }
  ASSERT_TRUE(q.Read(named, Named("a"), &any_face).ok());
  ASSERT_TRUE(q.Read({}, {}, ids, Named("a"), &by_id).ok());
  std::vector<int32_t> shifted(ids.begin() + 1, ids.end());
  shifted.push_back(ids.front());
  EnginePoints targets;
  ASSERT_TRUE(q.Read({}, {}, shifted, Named("b"), &targets).ok());
  std::vector<double> from_faces(ids.size()), from_ids(ids.size());
  ASSERT_TRUE(q.DistanceBatch(any_face, targets, from_faces).ok());
  ASSERT_TRUE(q.DistanceBatch(by_id, targets, from_ids).ok());
  EXPECT_EQ(from_faces, from_ids);

  // A path from a vertex starts at it, in the face VertexPoint chose.
  absl::StatusOr<std::vector<PathPoint>> path = q.Path(by_id, 3, targets, 3, 0);
  ASSERT_TRUE(path.ok()) << path.status();
  EXPECT_EQ(path->front().point.face, q.VertexPoint(3)->face);
  EXPECT_LT((path->front().position - sphere.position(3)).norm(), 1e-12);

  // Mixed: vertex 5, then a face point.
  const std::vector<int32_t> mixed_ids = {5, -1};
  const std::vector<int32_t> faces = {0, 3};
  const std::vector<double> weights = {0, 0, 0, 0.2, 0.3, 0.5};
  EnginePoints mixed, alone;
  ASSERT_TRUE(q.Read(faces, weights, mixed_ids, Named("m"), &mixed).ok());
  const std::vector<SurfacePoint> both = {*q.VertexPoint(5), SurfacePoint{3, {0.2, 0.3, 0.5}}};
  ASSERT_TRUE(q.Read(both, Named("m"), &alone).ok());
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(mixed.engine_point(i).face, alone.engine_point(i).face);
    EXPECT_EQ(mixed.engine_point(i).w, alone.engine_point(i).w);
  }

  EnginePoints bad;
  absl::Status status = q.Read({}, {}, std::vector<int32_t>{0, q.num_vertices()}, Named("a"), &bad);
  EXPECT_EQ(status.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(std::string(status.message()), ::testing::StartsWith("a[1]: vertex id"));
  status = q.Read({}, {}, std::vector<int32_t>{-1}, Named("a"), &bad);
  EXPECT_EQ(status.code(), absl::StatusCode::kOutOfRange);
  status = q.Read({}, {}, std::vector<int32_t>{lonely}, Named("a"), &bad);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), ::testing::HasSubstr("on no face"));
  status = q.Read(faces, weights, std::vector<int32_t>{5}, Named("m"), &bad);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
}

// The field within a radius against the exact whole-mesh field (the
// window engine on the same mesh, no radius): equal to 1e-9 relative at
// every vertex within r, and exactly those vertices listed.
void ExpectExactWithin(const RadiusField& field, const geodesic::ExactGeodesicSolver& exact,
                       int32_t num_vertices, double radius) {
  ASSERT_EQ(field.vertices.size(), field.distance.size());
  ASSERT_EQ(field.vertices.size(), field.nearest.size());
  EXPECT_TRUE(std::is_sorted(field.vertices.begin(), field.vertices.end()));
  size_t k = 0;
  for (int32_t v = 0; v < num_vertices; ++v) {
    const double truth = exact.VertexDistance(v);
    const bool listed = k < field.vertices.size() && field.vertices[k] == v;
    // A vertex on the circle itself may fall either side by rounding.
    if (std::abs(truth - radius) > 1e-9 * radius) {
      EXPECT_EQ(listed, truth <= radius) << "vertex " << v << " at " << truth;
    }
    if (!listed) continue;
    EXPECT_LE(field.distance[k], radius);
    EXPECT_NEAR(field.distance[k], truth, 1e-9 * truth) << "vertex " << v;
    if (truth <= radius) {
      EXPECT_EQ(field.nearest[k], exact.NearestSource(v)) << "vertex " << v;
    }
    ++k;
  }
  EXPECT_EQ(k, field.vertices.size()) << "vertices past the mesh's";
}

TEST(InputQueriesTest, FieldWithinIsTheExactFieldInsideTheRadius) {
  const mesh::Mesh torus = mesh::gen::Torus(40, 16, 1.0, 0.4);
  Built b = Build(RawOf(torus, "torus"), 60);
  auto queries = InputQueries::Create(b.engine);
  ASSERT_TRUE(queries.ok()) << queries.status();
  const double L = (*queries)->scale_length();
  geodesic::ExactGeodesicSolver exact(torus);
  QueryScratch scratch;
  // One source in a face, then two (a vertex and a point on an edge).
  const std::vector<std::vector<SurfacePoint>> source_sets = {
      {{17, {0.2, 0.3, 0.5}}}, {{300, {1, 0, 0}}, {900, {0.5, 0.5, 0}}}};
  for (const std::vector<SurfacePoint>& sources : source_sets) {
    EnginePoints read;
    ASSERT_TRUE((*queries)->Read(sources, Named("sources"), &read).ok());
    ASSERT_TRUE(exact.Propagate(sources).ok());
    size_t previous = 0;
    for (const double radius : {L, 3 * L, 100.0}) {
      SCOPED_TRACE(::testing::Message() << sources.size() << " sources, radius " << radius);
      FieldWithinOptions options;
      options.radius = radius;
      absl::StatusOr<RadiusField> field = (*queries)->FieldWithin(read, options, &scratch);
      ASSERT_TRUE(field.ok()) << field.status();
      ExpectExactWithin(*field, exact, torus.num_vertices(), radius);
      EXPECT_GT(field->vertices.size(), previous);
      previous = field->vertices.size();
      if (radius < 2 * L) {
        EXPECT_LT(field->vertices.size(), torus.num_vertices() / 4u);
      }
      if (sources.size() == 2) {
        EXPECT_NE(std::find(field->nearest.begin(), field->nearest.end(), 1), field->nearest.end());
      }
    }
    EXPECT_EQ(previous, static_cast<size_t>(torus.num_vertices()));  // r = 100: all of it
  }
  // Without a scratch of the caller's, the same answer.
  EnginePoints read;
  ASSERT_TRUE((*queries)->Read(source_sets[0], Named("sources"), &read).ok());
  FieldWithinOptions options;
  options.radius = 2 * L;
  absl::StatusOr<RadiusField> with = (*queries)->FieldWithin(read, options, &scratch);
  absl::StatusOr<RadiusField> without = (*queries)->FieldWithin(read, options);
  ASSERT_TRUE(with.ok() && without.ok());
  EXPECT_EQ(with->vertices, without->vertices);
  EXPECT_EQ(with->distance, without->distance);
}

TEST(InputQueriesTest, FieldWithinRefusesBadRadiiAndTooManyVertices) {
  const mesh::Mesh sphere = mesh::gen::Sphere(2, 1.0);
  Built b = Build(RawOf(sphere, "sphere"), 40);
  auto queries = InputQueries::Create(b.engine);
  ASSERT_TRUE(queries.ok()) << queries.status();
  const SurfacePoint source{5, {0.2, 0.3, 0.5}};
  EnginePoints read;
  ASSERT_TRUE((*queries)->Read(std::span(&source, 1), Named("sources"), &read).ok());
  for (const auto& [radius, shown] : std::vector<std::pair<double, std::string>>{
           {NAN, "nan"}, {INFINITY, "inf"}, {-1.0, "-1"}, {0.0, "0"}}) {
    FieldWithinOptions options;
    options.radius = radius;
    const absl::Status status = (*queries)->FieldWithin(read, options).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << shown;
    EXPECT_THAT(std::string(status.message()), ::testing::EndsWith("got " + shown));
  }
  FieldWithinOptions options;
  options.radius = 1.0;
  EnginePoints none;
  EXPECT_EQ((*queries)->FieldWithin(none, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  absl::StatusOr<RadiusField> all = (*queries)->FieldWithin(read, options);
  ASSERT_TRUE(all.ok()) << all.status();
  options.max_vertices = static_cast<int64_t>(all->vertices.size()) / 2;
  const absl::Status over = (*queries)->FieldWithin(read, options).status();
  EXPECT_EQ(over.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(std::string(over.message()),
              ::testing::HasSubstr(absl::StrFormat("more than %d vertices", options.max_vertices)));
  options.max_vertices = sphere.num_vertices();
  EXPECT_TRUE((*queries)->FieldWithin(read, options).ok());
}

// Over a split index the field lists input vertices only, with the coarse
// mesh's exact distances (the split is flat); over a repaired one, a split
// vertex once, at its nearest copy.
TEST(InputQueriesTest, FieldWithinAnswersInTheInputIds) {
  const mesh::Mesh coarse = mesh::gen::Sphere(1, 1.0);
  Built b = Build(RawOf(coarse, "sphere"), 120, /*refine=*/true);
  ASSERT_GT(b.engine->index().num_vertices(), coarse.num_vertices());
  auto queries = InputQueries::Create(b.engine);
  ASSERT_TRUE(queries.ok()) << queries.status();
  const std::vector<SurfacePoint> sources = {{3, {0.2, 0.3, 0.5}}, {60, {0, 1, 0}}};
  EnginePoints read;
  ASSERT_TRUE((*queries)->Read(sources, Named("sources"), &read).ok());
  geodesic::ExactGeodesicSolver exact(coarse);
  ASSERT_TRUE(exact.Propagate(sources).ok());
  for (const double radius : {0.5, 1.2}) {
    FieldWithinOptions options;
    options.radius = radius;
    absl::StatusOr<RadiusField> field = (*queries)->FieldWithin(read, options);
    ASSERT_TRUE(field.ok()) << field.status();
    ASSERT_FALSE(field->vertices.empty());
    ExpectExactWithin(*field, exact, coarse.num_vertices(), radius);
  }

  Built pyramids = Build(mesh::testing::TwoPyramidsApexToApex(), 10);
  auto apart = InputQueries::Create(pyramids.engine);
  ASSERT_TRUE(apart.ok());
  ASSERT_EQ(pyramids.engine->index().vertex_copies().size(), 1u);
  const SurfacePoint on_first{0, {0.2, 0.3, 0.5}};
  ASSERT_TRUE((*apart)->Read(std::span(&on_first, 1), Named("sources"), &read).ok());
  FieldWithinOptions options;
  options.radius = 100;
  absl::StatusOr<RadiusField> field = (*apart)->FieldWithin(read, options);
  ASSERT_TRUE(field.ok()) << field.status();
  absl::StatusOr<DistanceField> whole = (*apart)->Field(read);
  ASSERT_TRUE(whole.ok());
  // The reachable input vertices, each once; the whole field's at the apex
  // (vertex 0, reached through its copy on the first pyramid) is O(1), so
  // only listed vertices are compared, loosely.
  std::vector<int32_t> reachable;
  for (int32_t v = 0; v < 9; ++v) {
    if (std::isfinite(whole->distance[v])) reachable.push_back(v);
  }
  EXPECT_EQ(field->vertices, reachable);
  for (size_t i = 0; i < field->vertices.size(); ++i) {
    EXPECT_NEAR(field->distance[i], whole->distance[field->vertices[i]],
                0.05 + 0.05 * field->distance[i]);
  }
}

}  // namespace
}  // namespace geodex::query
