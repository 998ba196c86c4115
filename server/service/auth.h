#pragma once

// Bearer-token authentication of the Geodex service. A call must carry the
// metadata "authorization: Bearer <token>" with one of the configured tokens;
// otherwise it fails with UNAUTHENTICATED before any work is done. The health
// and reflection services stay open (probes and tooling do not hold tokens).
//
// Tokens are compared in constant time. Use with TLS: over plaintext the
// token travels in the clear.
//
// Thread safety: immutable; Check is safe from any thread.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "grpcpp/server_context.h"

namespace geodex::server {

class TokenAuth {
 public:
  // Tokens from a file, one per line (several allow rotation); blank lines
  // and lines starting with '#' are ignored, surrounding whitespace trimmed.
  // Errors: NotFound / PermissionDenied if unreadable; InvalidArgument if it
  // holds no token.
  static absl::StatusOr<TokenAuth> FromFile(const std::string& path);
  // The token in environment variable `variable`. Errors: NotFound if unset
  // or empty.
  static absl::StatusOr<TokenAuth> FromEnv(const std::string& variable);

  explicit TokenAuth(std::vector<std::string> tokens) : tokens_(std::move(tokens)) {}

  // OK if `authorization` (the header's value, if present) is "Bearer T" for
  // a configured token T. Errors: Unauthenticated, saying what is missing
  // (never echoing the token).
  absl::Status CheckHeader(std::optional<std::string_view> authorization) const;
  // CheckHeader on the call's "authorization" metadata.
  absl::Status Check(const grpc::CallbackServerContext& context) const;

 private:
  std::vector<std::string> tokens_;
};

}  // namespace geodex::server
