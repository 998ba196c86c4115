#pragma once

// The gRPC implementation of GeodexConnection (no retries; MakeGrpcConnection
// in client.h adds them).

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "geodex/client/connection.h"
#include "geodex/client/options.h"

namespace geodex::client {

// `target` as gRPC should see it: a comma-separated list of IP literals with
// ports becomes "ipv4:a,b" or "ipv6:a,b"; anything else is passed on as is.
// Errors: INVALID_ARGUMENT for an empty target or a list that mixes address
// families or holds a name (names need "dns:///name:port").
absl::StatusOr<std::string> NormalizeTarget(const std::string& target);

// A connection over one gRPC channel to `target`. Errors as MakeGrpcConnection.
absl::StatusOr<std::shared_ptr<GeodexConnection>> MakeGrpcConnectionNoRetry(
    const std::string& target, const ConnectOptions& options);

}  // namespace geodex::client
