// libFuzzer target: the server's reading of requests (server/convert.h)
// and the engine calls behind them, in process (no gRPC). The first byte
// picks the message, the rest is its wire encoding:
//   even: geodex.v1.DistanceRequest -> options, PointsFromProto,
//         QueryEngine::DistanceBatch (GeodexService::ComputeDistances)
//   odd:  geodex.v1.LocateRequest -> PositionsFromProto, QueryEngine::Locate
// against a small generated model (fuzz_model.h).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "geodex/v1/geodex.pb.h"
#include "server/convert.h"
#include "tests/fuzz/fuzz_model.h"

namespace {

using geodex::query::DistanceOptions;
using geodex::query::NearPairs;

// GeodexService's DistanceOptionsFor for a model whose config sets nothing
// (that function lives in the gRPC service library, which the fuzz tree does
// not build): unknown or contradictory modes and bad tolerances are refused.
bool OptionsFor(const geodex::v1::DistanceRequest& request, DistanceOptions* options) {
  const int requested = request.near_pairs();
  if (!geodex::v1::NearPairs_IsValid(requested)) return false;
  if (request.exact_near_pairs() && requested != geodex::v1::NEAR_PAIRS_UNSPECIFIED &&
      requested != geodex::v1::NEAR_PAIRS_EXACT) {
    return false;
  }
  switch (static_cast<geodex::v1::NearPairs>(requested)) {
    case geodex::v1::NEAR_PAIRS_UNFOLD:
      options->near_pairs = NearPairs::kUnfold;
      break;
    case geodex::v1::NEAR_PAIRS_EXACT:
      options->near_pairs = NearPairs::kExact;
      break;
    default:
      options->near_pairs = NearPairs::kPath;
      break;
  }
  if (request.exact_near_pairs()) options->near_pairs = NearPairs::kExact;
  const double tolerance = request.tolerance();
  if (!(tolerance >= 0) || !std::isfinite(tolerance)) return false;
  options->tolerance = tolerance;
  return true;
}

void FuzzDistance(const geodex::v1::DistanceRequest& request) {
  const geodex::query::InputQueries& queries = geodex::fuzz::FuzzQueries();
  const int64_t n = geodex::server::PointCount(request.a());
  if (n != geodex::server::PointCount(request.b())) return;
  DistanceOptions options;
  if (!OptionsFor(request, &options)) return;
  geodex::query::EnginePoints a, b;
  if (!geodex::server::PointsFromProto(request.a(), "a", queries, &a).ok()) return;
  if (!geodex::server::PointsFromProto(request.b(), "b", queries, &b).ok()) return;
  geodex::v1::DistanceResponse response;
  geodex::query::QueryScratch scratch;
  const absl::Status status = queries.DistanceBatch(
      a, b, geodex::server::ResizeForOutput(response.mutable_distances(), n), options, &scratch,
      request.error_bounds() ? geodex::server::ResizeForOutput(response.mutable_bounds(), n)
                             : std::span<double>());
  (void)status;
}

void FuzzLocate(const geodex::v1::LocateRequest& request) {
  const geodex::query::InputQueries& queries = geodex::fuzz::FuzzQueries();
  std::vector<geodex::mesh::Vec3> positions;
  if (!geodex::server::PositionsFromProto(request.positions(), "positions", &positions).ok()) {
    return;
  }
  geodex::v1::LocateResponse response;
  for (const geodex::mesh::Vec3& x : positions) {
    auto located = queries.Locate(x);
    if (!located.ok()) return;
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
