// libFuzzer target: the server's reading of requests (server/convert/convert.h)
// and the engine calls behind them, in process (no gRPC). The first byte
// picks the message, the rest is its wire encoding:
//   even: geodex.v1.DistanceRequest -> CheckPairedUp, DistanceOptionsFor,
//         PointsFromProto, InputQueries::DistanceBatch (as
//         server/service/compute_distances.cc runs them)
//   odd:  geodex.v1.LocateRequest -> PositionsFromProto, InputQueries::Locate
// against a small generated model (fuzz_model.h) with the default
// configuration. A request the conversion accepts must be answered: an error
// from the engine then aborts, and libFuzzer reports the input.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "geodex/v1/geodex.pb.h"
#include "server/config/model_config.pb.h"
#include "server/convert/convert.h"
#include "tests/fuzz/fuzz_model.h"

namespace {

// Aborts with `status` (an engine error on input the conversion accepted).
[[noreturn]] void Fail(const char* what, const absl::Status& status) {
  std::fprintf(stderr, "%s failed on a request the server accepts: %s\n", what,
               status.ToString().c_str());
  std::abort();
}

void FuzzDistance(const geodex::v1::DistanceRequest& request) {
  const geodex::query::InputQueries& queries = geodex::fuzz::FuzzQueries();
  if (!geodex::server::CheckPairedUp(request.a(), request.b()).ok()) return;
  const absl::StatusOr<geodex::query::DistanceOptions> options = geodex::server::DistanceOptionsFor(
      geodex::server::ModelConfig(), geodex::server::DistanceChoice::Of(request));
  if (!options.ok()) return;  // an unknown or contradictory choice
  geodex::query::EnginePoints a, b;
  if (!geodex::server::PointsFromProto(request.a(), "a", queries, &a).ok()) return;
  if (!geodex::server::PointsFromProto(request.b(), "b", queries, &b).ok()) return;
  const int64_t n = geodex::server::PointCount(request.a());
  geodex::v1::DistanceResponse response;
  geodex::query::QueryScratch scratch;
  const absl::Status status = queries.DistanceBatch(
      a, b, geodex::server::ResizeForOutput(response.mutable_distances(), n), *options, &scratch,
      request.error_bounds() ? geodex::server::ResizeForOutput(response.mutable_bounds(), n)
                             : std::span<double>());
  if (!status.ok()) Fail("DistanceBatch", status);
}

void FuzzLocate(const geodex::v1::LocateRequest& request) {
  const geodex::query::InputQueries& queries = geodex::fuzz::FuzzQueries();
  std::vector<geodex::mesh::Vec3> positions;
  if (!geodex::server::PositionsFromProto(request.positions(), "positions", &positions).ok()) {
    return;
  }
  geodex::v1::LocateResponse response;
  for (const geodex::mesh::Vec3& x : positions) {
    const absl::StatusOr<geodex::query::LocatedPoint> located = queries.Locate(x);
    if (!located.ok()) Fail("Locate", located.status());
    geodex::server::AppendLocated(*located, &response);
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  geodex::fuzz::FuzzQueries();  // built before the first input is timed
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const uint8_t kind = data[0];
  ++data;
  --size;
  if (kind % 2 == 0) {
    geodex::v1::DistanceRequest request;
    if (request.ParseFromArray(data, static_cast<int>(size))) FuzzDistance(request);
  } else {
    geodex::v1::LocateRequest request;
    if (request.ParseFromArray(data, static_cast<int>(size))) FuzzLocate(request);
  }
  return 0;
}
