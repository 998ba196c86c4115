// `geodex web`: the viewer and the HTTP/JSON gateway
// (client/cli/web/web_gateway.h), a client of the gRPC server like any other
// verb, serving until SIGINT or SIGTERM. The URL goes to standard output once
// listening.

#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/web/web_gateway.h"
#include "client/cli/web/web_server.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct WebFlags {
  ConnectionFlags conn;
  WebServerOptions server;
  std::string assets;
  size_t max_body = 8 << 20;
};

absl::Status Web(WebFlags flags) {
  const std::string dir = flags.assets.empty() ? DefaultWebAssetsDir() : flags.assets;
  if (dir.empty()) {
    return InputError(absl::NotFoundError(
        "the viewer's files are not beside this binary (web/ or ../share/geodex/web/); "
        "name their directory with --assets"));
  }
  absl::StatusOr<WebAssets> assets = LoadWebAssets(dir);
  if (!assets.ok()) return InputError(assets.status());
  absl::StatusOr<Client> client = MakeClient(flags.conn);
  if (!client.ok()) return client.status();
  const WebGateway gateway(client->connection(), *std::move(assets), flags.max_body);
  flags.server.on_listening = [&conn = flags.conn](const std::string& url) {
    std::printf("geodex web: serving %s (geodex server %s)\n", url.c_str(), conn.server.c_str());
    std::fflush(stdout);
  };
  absl::Status status = ServeWeb(gateway, flags.server);
  if (absl::IsInvalidArgument(status)) return InputError(status);
  return status;
}

}  // namespace

void AddWebCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<WebFlags>();
  CLI::App* web = app->add_subcommand(
      "web",
      "Serve the web viewer and an HTTP/JSON gateway to this server's API (GET /v1/models, "
      "POST /v1/models/NAME:distance, ...) until interrupted");
  AddConnectionFlags(web, &flags->conn);
  web->add_option("--listen", flags->server.listen,
                  "HTTP address HOST:PORT (port 0: any free port; the URL is printed). Anyone "
                  "who reaches it uses this client's token: keep it on loopback or behind a proxy")
      ->capture_default_str();
  web->add_option("--assets", flags->assets,
                  "Directory of the viewer's files (default: beside the binary, or the installed "
                  "share/geodex/web)");
  web->add_option("--max-body", flags->max_body, "Largest request body, bytes (larger: 413)")
      ->check(CLI::Range(size_t{1}, size_t{1} << 30))
      ->capture_default_str();
  web->callback([flags, status] { *status = Web(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(100, AddWebCommand);

}  // namespace geodex::client::cli
