#include "server/service/compute_distances.h"

#include <algorithm>
#include <span>

#include "core/common/status_macros.h"
#include "server/convert/convert.h"

namespace geodex::server {

absl::Status ComputeDistances(const ResolvedModel& model, const ServiceLimits& limits,
                              const v1::SurfacePoints& a, const v1::SurfacePoints& b,
                              const DistanceChoice& choice, WorkerContext& worker,
                              google::protobuf::RepeatedField<double>* out,
                              google::protobuf::RepeatedField<double>* bounds) {
  const int64_t n = PointCount(a);
  GEODEX_RETURN_IF_ERROR(CheckPairsPerMessage(limits, std::max(n, PointCount(b))));
  GEODEX_RETURN_IF_ERROR(CheckPairedUp(a, b));
  GEODEX_ASSIGN_OR_RETURN(const query::DistanceOptions options,
                          DistanceOptionsFor(model.model->config, choice));
  const query::InputQueries& queries = model.version->queries();
  GEODEX_RETURN_IF_ERROR(PointsFromProto(a, "a", queries, &worker.a));
  GEODEX_RETURN_IF_ERROR(PointsFromProto(b, "b", queries, &worker.b));
  return queries.DistanceBatch(
      worker.a, worker.b, ResizeForOutput(out, n), options, &worker.scratch,
      choice.error_bounds ? ResizeForOutput(bounds, n) : std::span<double>());
}

}  // namespace geodex::server
