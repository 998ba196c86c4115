// Uses the installed geodex client: a Client over a hand-written connection
// (no server needed), and a real gRPC connection to a port with no server.
// Exit 0 when both behave as documented.

#include <cstdio>
#include <memory>
#include <vector>

#include "geodex/client/client.h"

namespace {

// d(a, b) = |a.face - b.face|, from a connection written by the consumer.
class FixedConnection : public geodex::client::GeodexConnection {
 public:
  absl::StatusOr<geodex::v1::DistanceResponse> Distance(
      const geodex::v1::DistanceRequest& request) override {
    geodex::v1::DistanceResponse response;
    for (int i = 0; i < request.a().faces_size(); ++i) {
      response.add_distances(std::abs(request.a().faces(i) - request.b().faces(i)));
    }
    return response;
  }
  // One triangle, in one chunk.
  absl::StatusOr<std::vector<geodex::v1::MeshChunk>> GetMesh(
      const geodex::v1::GetMeshRequest& request) override {
    geodex::v1::MeshChunk chunk;
    chunk.set_num_vertices(3);
    chunk.set_num_faces(1);
    chunk.set_version(request.model().version());
    for (double c : {0, 0, 0, 1, 0, 0, 0, 1, 0}) chunk.add_positions(c);
    for (uint32_t v : {0, 1, 2}) chunk.add_faces(v);
    return std::vector<geodex::v1::MeshChunk>{chunk};
  }
};

int Fail(const char* what) {
  std::fprintf(stderr, "consumer: %s\n", what);
  return 1;
}

}  // namespace

int main() {
  geodex::Client client(std::make_shared<FixedConnection>());
  std::vector<geodex::client::PointPair> pairs = {{{3, {1, 0, 0}}, {1, {0, 1, 0}}},
                                                  {{0, {1, 0, 0}}, {9, {0, 0, 1}}}};
  absl::StatusOr<std::vector<double>> d = client.Distance("demo", pairs);
  if (!d.ok() || d->size() != 2 || (*d)[0] != 2 || (*d)[1] != 9) {
    return Fail("Distance over a custom connection gave the wrong answer");
  }

  absl::StatusOr<geodex::client::Mesh> mesh = client.GetMesh({"demo", 4});
  if (!mesh.ok() || mesh->positions.size() != 3 || mesh->faces.size() != 1 || mesh->version != 4) {
    return Fail("GetMesh over a custom connection gave the wrong mesh");
  }

  geodex::client::ConnectOptions options;
  options.deadline = absl::Seconds(5);
  options.retry.max_attempts = 1;
  absl::StatusOr<geodex::Client> remote = geodex::client::Connect("127.0.0.1:1", options);
  if (!remote.ok()) return Fail("Connect failed although it does not dial");
  const absl::Status status = remote->ListModels().status();
  if (status.code() != absl::StatusCode::kUnavailable) {
    std::fprintf(stderr, "consumer: expected UNAVAILABLE, got %s\n", status.ToString().c_str());
    return 1;
  }
  std::printf("consumer: ok (distances %g %g; no server: %s)\n", (*d)[0], (*d)[1],
              absl::StatusCodeToString(status.code()).c_str());
  return 0;
}
