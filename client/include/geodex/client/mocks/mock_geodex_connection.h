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
#define GEODEX_CLIENT_MOCK_RPC(Name, Request, Result) \
  MOCK_METHOD(absl::StatusOr<Result>, Name, (const Request& request), (override));
  GEODEX_CLIENT_RPCS(GEODEX_CLIENT_MOCK_RPC)
#undef GEODEX_CLIENT_MOCK_RPC

  MOCK_METHOD(std::unique_ptr<DistanceStream>, StreamDistances, (const StreamOptions& options),
              (override));
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
