// A model built from a repaired mesh (core/mesh/mesh_repair.h) is asked and
// answers in the ids of its input mesh: a sphere with a duplicate face and
// re-oriented faces, over loopback; once as it is, once also refined flat
// (more samples than the sphere has vertices, so that its edges are split
// and samples sit on midpoints).

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_repair.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/server_testing.h"

namespace geodex::server {
namespace {

using testing::Context;
using testing::Ref;

// The sphere's triangles with face 7 repeated reversed (input face 320) and
// faces 5 and 40 flipped.
mesh::RawMesh BrokenSphere() {
  const mesh::Mesh sphere = mesh::gen::Sphere(2, 1.0);
  mesh::RawMesh raw;
  raw.name = "broken sphere";
  raw.positions = sphere.positions();
  raw.triangles = sphere.faces();
  const mesh::Triangle t = raw.triangles[7];
  raw.triangles.push_back({t[0], t[2], t[1]});
  for (int32_t f : {5, 40}) std::swap(raw.triangles[f][1], raw.triangles[f][2]);
  for (size_t f = 0; f < raw.triangles.size(); ++f) raw.input_face.push_back(f);
  return raw;
}

std::string RepairedIndexBytes(const mesh::RawMesh& raw, bool refine) {
  absl::StatusOr<mesh::RepairedMesh> repaired = mesh::RepairMesh(raw);
  EXPECT_TRUE(repaired.ok()) << repaired.status();
  const int32_t samples = refine ? 400 : 40;
  absl::StatusOr<builder::PreparedMesh> prepared =
      builder::PrepareMesh(repaired->mesh, builder::RecordRepair(*repaired), samples, refine);
  EXPECT_TRUE(prepared.ok()) << prepared.status();
  EXPECT_EQ(prepared->record.split_vertices > 0, refine);
  builder::BuildOptions options;
  options.num_samples = samples;
  options.threads = 2;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data = builder::BuildPreparedIndex(*prepared, options, &summary);
  EXPECT_TRUE(data.ok()) << data.status();
  absl::StatusOr<std::string> bytes = index::SerializeIndex(*data);
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  return *bytes;
}

v1::SurfacePoints Points(std::vector<mesh::SurfacePoint> points) {
  return testing::ToProto(points);
}

// The parameter: whether the model is refined as well.
class ServerRepairTest : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override {
    server_ = std::make_unique<testing::TestServer>();
    testing::WriteModelVersion(server_->root(), "repaired", 1,
                               RepairedIndexBytes(raw_, GetParam()));
    server_->Rescan();
    stub_ = v1::Geodex::NewStub(server_->TcpChannel());
  }
  double Distance(const mesh::SurfacePoint& a, const mesh::SurfacePoint& b) {
    v1::DistanceRequest request;
    *request.mutable_model() = Ref("repaired");
    *request.mutable_a() = Points({a});
    *request.mutable_b() = Points({b});
    v1::DistanceResponse response;
    auto context = Context();
    const grpc::Status s = stub_->Distance(context.get(), request, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return s.ok() ? response.distances(0) : NAN;
  }

  const mesh::RawMesh raw_ = BrokenSphere();
  std::unique_ptr<testing::TestServer> server_;
  std::unique_ptr<v1::Geodex::Stub> stub_;
};

TEST_P(ServerRepairTest, ModelCountsAndMeshAreTheInputs) {
  v1::GetModelRequest request;
  *request.mutable_model() = Ref("repaired");
  v1::ModelInfo info;
  auto context = Context();
  ASSERT_TRUE(stub_->GetModel(context.get(), request, &info).ok());
  EXPECT_EQ(info.num_faces(), 321);
  EXPECT_EQ(info.num_vertices(), 162);
  EXPECT_EQ(info.build_report().at("mesh_duplicate_faces_dropped"), "1");
  EXPECT_EQ(info.build_report().at("mesh_faces_reoriented"), "2");
  EXPECT_EQ(info.build_report().contains("mesh_split"), GetParam());

  v1::GetMeshRequest mesh_request;
  *mesh_request.mutable_model() = Ref("repaired");
  auto mesh_context = Context();
  auto reader = stub_->GetMesh(mesh_context.get(), mesh_request);
  std::vector<uint32_t> faces;
  int64_t positions = 0;
  v1::MeshChunk chunk;
  while (reader->Read(&chunk)) {
    EXPECT_EQ(chunk.num_faces(), 321u);
    faces.insert(faces.end(), chunk.faces().begin(), chunk.faces().end());
    positions += chunk.positions_size();
  }
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_EQ(positions, 3 * 162);
  ASSERT_EQ(faces.size(), 3 * raw_.triangles.size());
  for (size_t f = 0; f < raw_.triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(faces[3 * f + k], static_cast<uint32_t>(raw_.triangles[f][k])) << f;
    }
  }
}

TEST_P(ServerRepairTest, DuplicateAndReorientedFacesAnswerInInputIds) {
  const mesh::SurfacePoint far{150, {0.3, 0.3, 0.4}};
  // Face 320 is face 7 reversed: (w0, w1, w2) on 7 is (w0, w2, w1) on 320.
  EXPECT_EQ(Distance({320, {0.2, 0.5, 0.3}}, far), Distance({7, {0.2, 0.3, 0.5}}, far));
  // Face 321 is past the input's end.
  v1::DistanceRequest bad;
  *bad.mutable_model() = Ref("repaired");
  *bad.mutable_a() = Points({{321, {1, 0, 0}}});
  *bad.mutable_b() = Points({far});
  v1::DistanceResponse response;
  auto context = Context();
  EXPECT_EQ(stub_->Distance(context.get(), bad, &response).error_code(),
            grpc::StatusCode::OUT_OF_RANGE);

  // A path from the re-oriented face 5 starts there with the input's weights.
  v1::PathRequest path_request;
  *path_request.mutable_model() = Ref("repaired");
  *path_request.mutable_a() = Points({{5, {0.1, 0.2, 0.7}}});
  *path_request.mutable_b() = Points({far});
  v1::PathResponse paths;
  auto path_context = Context();
  ASSERT_TRUE(stub_->Path(path_context.get(), path_request, &paths).ok());
  const v1::SurfacePoints& points = paths.paths(0).points();
  ASSERT_GE(points.faces_size(), 2);
  EXPECT_EQ(points.faces(0), 5);
  EXPECT_NEAR(points.weights(1), 0.2, 1e-12);
  EXPECT_NEAR(points.weights(2), 0.7, 1e-12);
  EXPECT_EQ(points.faces(points.faces_size() - 1), 150);

  // Located points come back in input faces: the centre of face 40
  // (re-oriented) is located on it with the input's corner order.
  const auto& p = raw_.positions;
  const mesh::Triangle& t = raw_.triangles[40];
  const mesh::Vec3 x = 0.6 * p[t[0]] + 0.3 * p[t[1]] + 0.1 * p[t[2]];
  v1::LocateRequest locate;
  *locate.mutable_model() = Ref("repaired");
  for (int k = 0; k < 3; ++k) locate.mutable_positions()->add_xyz(x[k]);
  v1::LocateResponse located;
  auto locate_context = Context();
  ASSERT_TRUE(stub_->Locate(locate_context.get(), locate, &located).ok());
  EXPECT_EQ(located.points().faces(0), 40);
  EXPECT_NEAR(located.points().weights(0), 0.6, 1e-9);
  EXPECT_NEAR(located.points().weights(1), 0.3, 1e-9);
  EXPECT_NEAR(located.points().weights(2), 0.1, 1e-9);

  // A field has one value per input vertex.
  v1::DistanceFieldRequest field_request;
  *field_request.mutable_model() = Ref("repaired");
  *field_request.mutable_sources() = Points({{320, {1, 0, 0}}});
  auto field_context = Context();
  auto reader = stub_->DistanceField(field_context.get(), field_request);
  v1::DistanceFieldChunk chunk;
  int64_t values = 0;
  while (reader->Read(&chunk)) {
    EXPECT_EQ(chunk.num_vertices(), 162);
    for (double d : chunk.distances()) EXPECT_TRUE(std::isfinite(d));
    values += chunk.distances_size();
  }
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_EQ(values, 162);
}

// Samples are named by surface points in input faces; one on a midpoint of
// the refinement is no input vertex (-1).
TEST_P(ServerRepairTest, TriangulationNamesSamplesInInputIds) {
  v1::GetTriangulationRequest request;
  *request.mutable_model() = Ref("repaired");
  v1::TriangulationResponse response;
  auto context = Context();
  ASSERT_TRUE(stub_->GetTriangulation(context.get(), request, &response).ok());
  EXPECT_EQ(response.num_vertices(), 162);
  EXPECT_EQ(response.vertex_triangles_size(), 162);
  const int m = response.sample_vertices_size();
  ASSERT_EQ(response.sample_points().faces_size(), m);
  int midpoints = 0;
  for (int i = 0; i < m; ++i) {
    const int32_t v = response.sample_vertices(i);
    const int32_t f = response.sample_points().faces(i);
    ASSERT_TRUE(f >= 0 && f < 321) << i;
    // The surface point is at the sample's position.
    mesh::Vec3 x(0, 0, 0);
    for (int k = 0; k < 3; ++k) {
      x += response.sample_points().weights(3 * i + k) * raw_.positions[raw_.triangles[f][k]];
    }
    const mesh::Vec3 at(response.sample_positions().xyz(3 * i),
                        response.sample_positions().xyz(3 * i + 1),
                        response.sample_positions().xyz(3 * i + 2));
    EXPECT_LT((x - at).norm(), 1e-6) << i;
    if (v == -1) {
      ++midpoints;
    } else {
      ASSERT_TRUE(v >= 0 && v < 162) << i;
      EXPECT_LT((raw_.positions[v] - at).norm(), 1e-12) << i;
    }
  }
  if (GetParam()) {
    EXPECT_GT(m, 162);  // more samples than the input has vertices
    EXPECT_GT(midpoints, 0);
  } else {
    EXPECT_EQ(midpoints, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(RepairedAndRefined, ServerRepairTest, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "Refined" : "Repaired";
                         });

}  // namespace
}  // namespace geodex::server
