#include "geodex/client/connection.h"

namespace geodex::client {
namespace {

absl::Status NotImplemented(const char* method) {
  return absl::UnimplementedError(std::string("GeodexConnection::") + method +
                                  " is not implemented by this connection");
}

// What the default StreamDistances returns: fails every operation.
class FailedStream : public DistanceStream {
 public:
  explicit FailedStream(absl::Status status) : status_(std::move(status)) {}
  bool Write(const v1::DistanceBatch&) override { return false; }
  bool WritesDone() override { return false; }
  bool Read(v1::DistanceResult*) override { return false; }
  void Cancel() override {}
  absl::Status Finish() override { return status_; }

 private:
  absl::Status status_;
};

}  // namespace

absl::StatusOr<v1::ListModelsResponse> GeodexConnection::ListModels(const v1::ListModelsRequest&) {
  return NotImplemented("ListModels");
}
absl::StatusOr<v1::ModelInfo> GeodexConnection::GetModel(const v1::GetModelRequest&) {
  return NotImplemented("GetModel");
}
absl::StatusOr<v1::DistanceResponse> GeodexConnection::Distance(const v1::DistanceRequest&) {
  return NotImplemented("Distance");
}
std::unique_ptr<DistanceStream> GeodexConnection::StreamDistances(const StreamOptions&) {
  return std::make_unique<FailedStream>(NotImplemented("StreamDistances"));
}
absl::StatusOr<std::vector<v1::MatrixBlock>> GeodexConnection::Matrix(const v1::MatrixRequest&) {
  return NotImplemented("Matrix");
}
absl::StatusOr<v1::PathResponse> GeodexConnection::Path(const v1::PathRequest&) {
  return NotImplemented("Path");
}
absl::StatusOr<std::vector<v1::DistanceFieldChunk>> GeodexConnection::DistanceField(
    const v1::DistanceFieldRequest&) {
  return NotImplemented("DistanceField");
}
absl::StatusOr<v1::LocateResponse> GeodexConnection::Locate(const v1::LocateRequest&) {
  return NotImplemented("Locate");
}
absl::StatusOr<std::vector<v1::MeshChunk>> GeodexConnection::GetMesh(const v1::GetMeshRequest&) {
  return NotImplemented("GetMesh");
}
absl::StatusOr<std::vector<v1::ExpMapChunk>> GeodexConnection::ExpMap(const v1::ExpMapRequest&) {
  return NotImplemented("ExpMap");
}
absl::StatusOr<v1::TriangulationResponse> GeodexConnection::GetTriangulation(
    const v1::GetTriangulationRequest&) {
  return NotImplemented("GetTriangulation");
}

}  // namespace geodex::client
