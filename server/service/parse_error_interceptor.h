#pragma once

// gRPC's callback handlers (1.51) answer a request whose bytes do not parse
// as the method's message with UNIMPLEMENTED and no message, which tells a
// client that the method does not exist. This interceptor turns exactly that
// answer, on a method geodex.v1.Geodex defines (where no handler of ours ever
// gives it: they all name what they refuse), into INVALID_ARGUMENT saying
// what was wrong.

#include <memory>

#include "grpcpp/support/server_interceptor.h"

namespace geodex::server {

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>
MakeParseErrorInterceptorFactory();

}  // namespace geodex::server
