#include "server/service/service_resources.h"

#include "absl/strings/str_format.h"
#include "server/service/auth.h"

namespace geodex::server {

absl::Status ServiceResources::Authorize(const grpc::CallbackServerContext& context) const {
  return auth == nullptr ? absl::OkStatus() : auth->Check(context);
}

absl::StatusOr<ResolvedModel> ServiceResources::Resolve(const v1::ModelRef& ref, Call& call) const {
  absl::StatusOr<ResolvedModel> resolved = registry->Resolve(ref.name(), ref.version());
  if (resolved.ok()) call.model = resolved->model->name;
  return resolved;
}

ServiceLimits ServiceResources::LimitsFor(const ModelSnapshot& model) const {
  return WithModelLimits(limits, model.config.limits());
}

absl::Status ServiceResources::Busy() const {
  return absl::ResourceExhaustedError(
      absl::StrFormat("server busy: %d jobs queued for %d workers; retry later",
                      pool->queue_depth(), pool->threads()));
}

grpc::Status ServiceResources::Finish(const Call& call, const absl::Status& status) const {
  return FinishCall(call, status, metrics);
}

}  // namespace geodex::server
