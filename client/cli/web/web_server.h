#pragma once

// The HTTP server of `geodex web` (cpp-httplib): every request goes to a
// WebGateway. Runs until SIGINT or SIGTERM.

#include <cstddef>
#include <functional>
#include <string>

#include "absl/status/status.h"
#include "client/cli/web/web_gateway.h"

namespace geodex::client::cli {

struct WebServerOptions {
  // HOST:PORT or [IPV6]:PORT to listen on; port 0 picks a free one.
  std::string listen = "127.0.0.1:8080";
  // Called once listening, with the URL (e.g. "http://127.0.0.1:43127/").
  std::function<void(const std::string& url)> on_listening;
};

// Serves `gateway` until SIGINT or SIGTERM (installs handlers for both), then
// returns OK. Errors: INVALID_ARGUMENT for a malformed `listen`; UNAVAILABLE
// when the address cannot be bound.
absl::Status ServeWeb(const WebGateway& gateway, const WebServerOptions& options);

// Where the viewer's files are by default: beside the binary in a build tree
// (<dir of the binary>/web), else where `cmake --install` puts them
// (<dir of the binary>/../share/geodex/web). Empty if neither holds index.html.
std::string DefaultWebAssetsDir();

}  // namespace geodex::client::cli
