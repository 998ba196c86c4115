// Points given as vertex ids of the mesh file, through every transport of
// RpcTest (instantiated in server_rpc_test.cc).

#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/server_testing.h"

namespace geodex::server {
namespace {

using testing::Context;
using ::testing::HasSubstr;
using testing::Ref;
using testing::RpcTest;
using testing::ToProto;

// Points given as vertex ids (alone, or mixed with face points) answer as
// the vertex in the lowest face that holds it, and a path from one starts
// there; bad ids are refused with the point's name.
TEST_P(RpcTest, VertexIdsAnswerAsTheVertexInItsLowestFace) {
  const index::Index& ix = sphere_->index();
  const int32_t n = 40;
  // The sphere's index is of the unrepaired mesh: input ids are its ids.
  auto at_vertex = [&](int32_t v) {
    for (int32_t f = 0; f < ix.num_faces(); ++f) {
      for (int k = 0; k < 3; ++k) {
        if (ix.faces()[3 * f + k] != v) continue;
        mesh::SurfacePoint p{f, {0, 0, 0}};
        p.w[k] = 1;
        return p;
      }
    }
    return mesh::SurfacePoint{};
  };
  auto b = testing::RandomPoints(ix.num_faces(), n, 21);
  v1::DistanceRequest request;
  *request.mutable_model() = Ref("sphere");
  *request.mutable_b() = ToProto(b);
  for (int32_t i = 0; i < n; ++i) {
    request.mutable_a()->add_vertices(3 * i);
    // b mixes: every third point a vertex, the rest face points.
    request.mutable_b()->add_vertices(i % 3 == 0 ? i : -1);
  }
  v1::DistanceResponse response;
  ASSERT_TRUE(Distance(request, &response).ok());
  ASSERT_EQ(response.distances_size(), n);
  for (int32_t i = 0; i < n; ++i) {
    const mesh::SurfacePoint bi = i % 3 == 0 ? at_vertex(i) : b[i];
    EXPECT_EQ(response.distances(i), *sphere_->Distance(at_vertex(3 * i), bi)) << i;
  }

  v1::PathRequest path;
  *path.mutable_model() = Ref("sphere");
  path.mutable_a()->add_vertices(5);
  path.mutable_b()->add_vertices(17);
  v1::PathResponse paths;
  auto context = Context();
  ASSERT_TRUE(stub_->Path(context.get(), path, &paths).ok());
  const v1::Polyline& line = paths.paths(0);
  EXPECT_EQ(line.points().faces(0), at_vertex(5).face);
  const mesh::Vec3 start(ix.positions()[15], ix.positions()[16], ix.positions()[17]);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(line.positions().xyz(c), start[c], 1e-12);

  request.mutable_a()->set_vertices(1, ix.num_vertices());
  grpc::Status s = Distance(request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::OUT_OF_RANGE);
  EXPECT_THAT(s.error_message(), HasSubstr("a[1]: vertex id"));
  request.mutable_a()->set_vertices(1, 0);
  request.mutable_b()->mutable_faces()->RemoveLast();
  s = Distance(request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("vertex ids"));
}

}  // namespace
}  // namespace geodex::server
