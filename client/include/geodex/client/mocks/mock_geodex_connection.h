#pragma once

// gMock doubles of GeodexConnection and DistanceStream, for unit tests of code
// that uses geodex::client::Client without a server:
//
//   auto mock = std::make_shared<geodex::client::MockGeodexConnection>();
//   EXPECT_CALL(*mock, Distance).WillOnce([](const geodex::v1::DistanceRequest& r) {
//     geodex::v1::DistanceResponse response;
//     response.add_distances(1.5);
//     return response;
//   });
//   geodex::client::Client client(mock);
//
// Needs GoogleTest's gMock (GTest::gmock); the geodex::client library does not.

#include <memory>
#include <vector>

#include "geodex/client/connection.h"
#include "gmock/gmock.h"

namespace geodex::client {

class MockGeodexConnection : public GeodexConnection {
 public:
  MOCK_METHOD(absl::StatusOr<v1::ListModelsResponse>, ListModels,
              (const v1::ListModelsRequest& request), (override));
  MOCK_METHOD(absl::StatusOr<v1::ModelInfo>, GetModel, (const v1::GetModelRequest& request),
              (override));
  MOCK_METHOD(absl::StatusOr<v1::DistanceResponse>, Distance, (const v1::DistanceRequest& request),
              (override));
  MOCK_METHOD(std::unique_ptr<DistanceStream>, StreamDistances, (const StreamOptions& options),
              (override));
  MOCK_METHOD(absl::StatusOr<std::vector<v1::MatrixBlock>>, Matrix,
              (const v1::MatrixRequest& request), (override));
  MOCK_METHOD(absl::StatusOr<v1::PathResponse>, Path, (const v1::PathRequest& request), (override));
  MOCK_METHOD(absl::StatusOr<std::vector<v1::DistanceFieldChunk>>, DistanceField,
              (const v1::DistanceFieldRequest& request), (override));
  MOCK_METHOD(absl::StatusOr<v1::LocateResponse>, Locate, (const v1::LocateRequest& request),
              (override));
  MOCK_METHOD(absl::StatusOr<std::vector<v1::ExpMapChunk>>, ExpMap,
              (const v1::ExpMapRequest& request), (override));
  MOCK_METHOD(absl::StatusOr<std::vector<v1::MeshChunk>>, GetMesh,
              (const v1::GetMeshRequest& request), (override));
  MOCK_METHOD(absl::StatusOr<v1::TriangulationResponse>, GetTriangulation,
              (const v1::GetTriangulationRequest& request), (override));
};

// Note: Client::Distance writes and reads a stream from two threads at once;
// a mock stream used that way must be given actions that are safe for it (or
// use a hand-written fake that synchronizes, as client_test.cc does).
class MockDistanceStream : public DistanceStream {
 public:
  MOCK_METHOD(bool, Write, (const v1::DistanceBatch& batch), (override));
  MOCK_METHOD(bool, WritesDone, (), (override));
  MOCK_METHOD(bool, Read, (v1::DistanceResult * result), (override));
  MOCK_METHOD(void, Cancel, (), (override));
  MOCK_METHOD(absl::Status, Finish, (), (override));
};

}  // namespace geodex::client
