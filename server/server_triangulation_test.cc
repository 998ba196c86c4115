// GetTriangulation end to end (in-process and over loopback): the samples,
// geodesic triangles and per-vertex triangles of the served index, compared
// with the index itself, and its errors.

#include <cmath>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/server_testing.h"

namespace geodex::server {
namespace {

using testing::Context;
using ::testing::HasSubstr;
using testing::Ref;
using testing::RpcTest;

TEST_P(RpcTest, GetTriangulationIsTheIndexTriangulation) {
  v1::GetTriangulationRequest request;
  *request.mutable_model() = Ref("sphere");
  v1::TriangulationResponse response;
  auto context = Context();
  grpc::Status s = stub_->GetTriangulation(context.get(), request, &response);
  ASSERT_TRUE(s.ok()) << s.error_message();
  const index::Index& index = sphere_->index();
  EXPECT_EQ(response.version(), 1);
  EXPECT_EQ(response.num_vertices(), index.num_vertices());

  const int m = index.num_samples();
  ASSERT_GT(m, 3);
  ASSERT_EQ(response.sample_vertices_size(), m);
  ASSERT_EQ(response.sample_positions().xyz_size(), 3 * m);
  ASSERT_EQ(response.sample_points().faces_size(), m);
  ASSERT_EQ(response.sample_points().weights_size(), 3 * m);
  for (int i = 0; i < m; ++i) {
    const int32_t v = index.samples()[i];
    EXPECT_EQ(response.sample_vertices(i), v);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(response.sample_positions().xyz(3 * i + k), index.positions()[3 * v + k]);
    }
    // The surface point is the sample's vertex: weight 1 on it in a face that uses it.
    const int32_t f = response.sample_points().faces(i);
    ASSERT_GE(f, 0);
    ASSERT_LT(f, index.num_faces());
    int ones = 0;
    for (int k = 0; k < 3; ++k) {
      const double w = response.sample_points().weights(3 * i + k);
      if (w == 1) {
        ++ones;
        EXPECT_EQ(index.faces()[3 * f + k], v) << "sample " << i;
      } else {
        EXPECT_EQ(w, 0);
      }
    }
    EXPECT_EQ(ones, 1) << "sample " << i;
  }

  const int t = index.num_triangles();
  ASSERT_EQ(response.triangle_corners_size(), 3 * t);
  ASSERT_EQ(response.triangle_neighbors_size(), 3 * t);
  for (int i = 0; i < t; ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(response.triangle_corners(3 * i + k), index.triangles()[i].corner[k]);
      EXPECT_EQ(response.triangle_neighbors(3 * i + k), index.triangles()[i].neighbor[k]);
    }
  }
  ASSERT_EQ(response.vertex_triangles_size(), index.num_vertices());
  for (int v = 0; v < index.num_vertices(); ++v) {
    EXPECT_EQ(response.vertex_triangles(v), index.vertices()[v].triangle) << v;
  }

  // The sample points are valid query points: the distance between two
  // corners of a geodesic triangle is the matrix entry, within what two exact
  // computations of it differ by (the builder's propagation, stored in a
  // 24-bit code, and the query's refined answer).
  v1::DistanceRequest distance;
  *distance.mutable_model() = Ref("sphere");
  for (int i = 0; i < std::min(t, 20); ++i) {
    for (int k = 0; k < 2; ++k) {
      const int32_t c = response.triangle_corners(3 * i + k);
      v1::SurfacePoints* p = k == 0 ? distance.mutable_a() : distance.mutable_b();
      p->add_faces(response.sample_points().faces(c));
      for (int j = 0; j < 3; ++j) p->add_weights(response.sample_points().weights(3 * c + j));
    }
  }
  v1::DistanceResponse answer;
  ASSERT_TRUE(Distance(distance, &answer).ok());
  for (int i = 0; i < answer.distances_size(); ++i) {
    const int32_t c0 = response.triangle_corners(3 * i), c1 = response.triangle_corners(3 * i + 1);
    EXPECT_NEAR(answer.distances(i), index.SampleDistance(c0, c1),
                1e-5 * (1 + index.SampleDistance(c0, c1)))
        << "triangle " << i;
  }
}

TEST_P(RpcTest, GetTriangulationErrors) {
  v1::GetTriangulationRequest request;
  v1::TriangulationResponse response;
  *request.mutable_model() = Ref("nope");
  auto context = Context();
  grpc::Status s = stub_->GetTriangulation(context.get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(s.error_message(), HasSubstr("nope"));
  *request.mutable_model() = Ref("../sphere");
  context = Context();
  EXPECT_EQ(stub_->GetTriangulation(context.get(), request, &response).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  *request.mutable_model() = Ref("sphere", 9);
  context = Context();
  EXPECT_EQ(stub_->GetTriangulation(context.get(), request, &response).error_code(),
            grpc::StatusCode::NOT_FOUND);
}

}  // namespace
}  // namespace geodex::server
