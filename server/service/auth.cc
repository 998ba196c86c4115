#include "server/service/auth.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_format.h"

namespace geodex::server {
namespace {

// Equal contents, in time that depends only on the lengths.
bool ConstantTimeEquals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

}  // namespace

absl::StatusOr<TokenAuth> TokenAuth::FromFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    const int err = errno;
    const std::string message = absl::StrFormat("token file %s: %s", path, std::strerror(err));
    return err == EACCES ? absl::PermissionDeniedError(message) : absl::NotFoundError(message);
  }
  std::vector<std::string> tokens;
  std::string line;
  while (std::getline(in, line)) {
    std::string token(absl::StripAsciiWhitespace(line));
    if (token.empty() || token[0] == '#') continue;
    tokens.push_back(std::move(token));
  }
  if (tokens.empty()) {
    return absl::InvalidArgumentError(absl::StrFormat("token file %s holds no token", path));
  }
  return TokenAuth(std::move(tokens));
}

absl::StatusOr<TokenAuth> TokenAuth::FromEnv(const std::string& variable) {
  const char* value = std::getenv(variable.c_str());
  std::string token(absl::StripAsciiWhitespace(value == nullptr ? "" : value));
  if (token.empty()) {
    return absl::NotFoundError(
        absl::StrFormat("environment variable %s is not set or empty", variable));
  }
  return TokenAuth({std::move(token)});
}

absl::Status TokenAuth::CheckHeader(std::optional<std::string_view> authorization) const {
  if (!authorization.has_value()) {
    return absl::UnauthenticatedError("missing 'authorization: Bearer <token>' metadata");
  }
  constexpr std::string_view kScheme = "Bearer ";
  if (authorization->size() < kScheme.size() ||
      !absl::EqualsIgnoreCase(std::string(authorization->substr(0, kScheme.size())),
                              std::string(kScheme))) {
    return absl::UnauthenticatedError("authorization metadata is not 'Bearer <token>'");
  }
  const std::string_view presented = authorization->substr(kScheme.size());
  bool match = false;
  for (const std::string& token : tokens_) match |= ConstantTimeEquals(presented, token);
  if (!match) return absl::UnauthenticatedError("invalid bearer token");
  return absl::OkStatus();
}

absl::Status TokenAuth::Check(const grpc::CallbackServerContext& context) const {
  const auto& metadata = context.client_metadata();
  auto it = metadata.find("authorization");
  if (it == metadata.end()) return CheckHeader(std::nullopt);
  return CheckHeader(std::string_view(it->second.data(), it->second.size()));
}

}  // namespace geodex::server
