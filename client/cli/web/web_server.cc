#include "client/cli/web/web_server.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <thread>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "httplib.h"

namespace geodex::client::cli {
namespace {

std::atomic<bool> stop_requested{false};

extern "C" void OnStopSignal(int) { stop_requested = true; }

struct HostPort {
  std::string host;
  int port = 0;
};

absl::StatusOr<HostPort> ParseListen(const std::string& listen) {
  const size_t colon = listen.rfind(':');
  auto bad = [&] {
    return absl::InvalidArgumentError(
        absl::StrCat("--listen '", listen, "' is not HOST:PORT or [IPV6]:PORT"));
  };
  if (colon == std::string::npos || colon == 0) return bad();
  HostPort out;
  out.host = listen.substr(0, colon);
  if (out.host.size() > 2 && out.host.front() == '[' && out.host.back() == ']') {
    out.host = out.host.substr(1, out.host.size() - 2);
  }
  if (!absl::SimpleAtoi(listen.substr(colon + 1), &out.port) || out.port < 0 || out.port > 65535) {
    return bad();
  }
  return out;
}

// httplib compresses answers with brotli when the client accepts it, at
// brotli's slowest quality: ten seconds for the JSON of a 100K-vertex mesh
// that gzip compresses in a fraction of one. Offer it gzip only. (The
// request is httplib's own mutable object, handed to us as const.)
void OfferGzipOnly(httplib::Server& server) {
  server.set_pre_routing_handler([](const httplib::Request& req, httplib::Response&) {
    auto& headers = const_cast<httplib::Request&>(req).headers;
    auto it = headers.find("Accept-Encoding");
    if (it != headers.end()) {
      const bool gzip = it->second.find("gzip") != std::string::npos;
      headers.erase(it);
      if (gzip) headers.emplace("Accept-Encoding", "gzip");
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
}

// Every method on every path goes to the gateway.
void RouteToGateway(httplib::Server& server, const WebGateway& gateway) {
  auto handle = [&gateway](const httplib::Request& req, httplib::Response& res) {
    HttpRequest request;
    request.method = req.method;
    request.path = req.path;
    // The URL's query only: httplib also puts a form-encoded body's fields
    // in req.params (curl -d sends that content type).
    if (const size_t q = req.target.find('?'); q != std::string::npos) {
      httplib::Params params;
      httplib::detail::parse_query_text(req.target.substr(q + 1), params);
      request.query.insert(params.begin(), params.end());
    }
    request.body = req.body;
    HttpResponse response = gateway.Handle(request);
    res.status = response.status;
    res.set_header("Cache-Control", "no-cache");
    res.set_content(std::move(response.body), response.content_type.c_str());
  };
  for (const char* pattern : {R"(/.*)"}) {
    server.Get(pattern, handle);
    server.Post(pattern, handle);
    server.Put(pattern, handle);
    server.Patch(pattern, handle);
    server.Delete(pattern, handle);
  }
}

// Rejections made by httplib itself (413 over --max-body, 400 for a
// malformed request, 404 for a method it has no route for) get the same JSON
// error body as the gateway's.
void AnswerRejectionsAsJson(httplib::Server& server) {
  server.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;
    const absl::StatusCode code = res.status == 413   ? absl::StatusCode::kResourceExhausted
                                  : res.status == 404 ? absl::StatusCode::kNotFound
                                  : res.status < 500  ? absl::StatusCode::kInvalidArgument
                                                      : absl::StatusCode::kInternal;
    const std::string message =
        res.status == 413 ? "the body exceeds the limit (--max-body)"
                          : absl::StrCat("the HTTP server rejected the request (", res.status, ")");
    const HttpResponse error = ErrorResponse(absl::Status(code, message), res.status);
    res.set_content(error.body, error.content_type.c_str());
  });
  server.set_exception_handler(
      [](const httplib::Request&, httplib::Response& res, std::exception_ptr) {
        const HttpResponse error = ErrorResponse(absl::InternalError("the gateway failed"));
        res.status = error.status;
        res.set_content(error.body, error.content_type.c_str());
      });
}

// The port bound at `address` (any free one for port 0); 0 when none is.
int Bind(httplib::Server& server, const HostPort& address) {
  int port = address.port;
  if (port == 0) {
    port = server.bind_to_any_port(address.host);
    if (port < 0) port = 0;
  } else if (!server.bind_to_port(address.host, port)) {
    port = 0;
  }
  return port;
}

void InstallStopHandlers() {
  stop_requested = false;
  struct sigaction action = {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

}  // namespace

absl::Status ServeWeb(const WebGateway& gateway, const WebServerOptions& options) {
  absl::StatusOr<HostPort> address = ParseListen(options.listen);
  if (!address.ok()) return address.status();

  httplib::Server server;
  server.set_payload_max_length(gateway.max_body_bytes());
  OfferGzipOnly(server);
  RouteToGateway(server, gateway);
  AnswerRejectionsAsJson(server);
  const int port = Bind(server, *address);
  if (port == 0) {
    return absl::UnavailableError(absl::StrCat("cannot listen on ", options.listen));
  }

  InstallStopHandlers();
  // A signal handler may not call stop(); a watcher thread does.
  std::thread watcher([&server] {
    while (!stop_requested) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    server.stop();
  });

  const bool ipv6 = address->host.find(':') != std::string::npos;
  if (options.on_listening) {
    options.on_listening(
        absl::StrCat("http://", ipv6 ? "[" : "", address->host, ipv6 ? "]" : "", ":", port, "/"));
  }
  server.listen_after_bind();
  stop_requested = true;  // listen ended on its own (an error): release the watcher
  watcher.join();
  return absl::OkStatus();
}

std::string DefaultWebAssetsDir() {
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return "";
  for (const std::filesystem::path& dir :
       {exe.parent_path() / "web", exe.parent_path().parent_path() / "share" / "geodex" / "web"}) {
    if (std::filesystem::exists(dir / "index.html", error)) return dir.string();
  }
  return "";
}

}  // namespace geodex::client::cli
