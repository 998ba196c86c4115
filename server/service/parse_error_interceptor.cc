#include "server/service/parse_error_interceptor.h"

#include <string>
#include <utility>

#include "absl/container/flat_hash_set.h"
#include "geodex/v1/geodex.pb.h"

namespace geodex::server {
namespace {

// "/geodex.v1.Geodex/Method" of every method the service defines (an unknown
// method keeps its UNIMPLEMENTED).
const absl::flat_hash_set<std::string>& ServiceMethods() {
  static const auto* methods = [] {
    auto* set = new absl::flat_hash_set<std::string>;
    const google::protobuf::ServiceDescriptor* service =
        v1::DistanceRequest::descriptor()->file()->FindServiceByName("Geodex");
    for (int i = 0; service != nullptr && i < service->method_count(); ++i) {
      set->insert("/" + service->full_name() + "/" + service->method(i)->name());
    }
    return set;
  }();
  return *methods;
}

class ParseErrorInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit ParseErrorInterceptor(std::string method) : method_(std::move(method)) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    using grpc::experimental::InterceptionHookPoints;
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_STATUS)) {
      const grpc::Status status = methods->GetSendStatus();
      if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED &&
          status.error_message().empty()) {
        methods->ModifySendStatus(grpc::Status(
            grpc::StatusCode::INVALID_ARGUMENT,
            "the request is not a valid protobuf message of " + method_ + "'s request type"));
      }
    }
    methods->Proceed();
  }

 private:
  const std::string method_;
};

class ParseErrorInterceptorFactory final
    : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override {
    if (!ServiceMethods().contains(info->method())) return nullptr;
    return new ParseErrorInterceptor(info->method());
  }
};

}  // namespace

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>
MakeParseErrorInterceptorFactory() {
  return std::make_unique<ParseErrorInterceptorFactory>();
}

}  // namespace geodex::server
