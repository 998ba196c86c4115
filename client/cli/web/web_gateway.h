#pragma once

// The HTTP/JSON side of `geodex web`: transcodes HTTP requests to the
// geodex.v1 calls of a GeodexConnection, in the style of Google's HTTP API
// rules and grpc-gateway, and serves the viewer's files. Independent of the
// HTTP server (client/cli/web/web_server.h feeds it), so that it is tested
// with MockGeodexConnection and no sockets.
//
// Routes (bodies and answers in protobuf's JSON mapping of the geodex.v1
// messages: lowerCamelCase names, unpopulated fields printed, int64 as
// strings, +Infinity as "Infinity"):
//
//   GET  /v1/models                          ListModels          -> ListModelsResponse
//   GET  /v1/models/{name}                   GetModel            -> ModelInfo
//   GET  /v1/models/{name}/mesh              GetMesh             -> MeshChunk (all chunks merged)
//   GET  /v1/models/{name}/triangulation     GetTriangulation    -> TriangulationResponse
//   POST /v1/models/{name}:distance          DistanceRequest     -> DistanceResponse
//   POST /v1/models/{name}:path              PathRequest         -> PathResponse
//   POST /v1/models/{name}:field             DistanceFieldRequest-> DistanceFieldChunk (merged)
//   POST /v1/models/{name}:locate            LocateRequest       -> LocateResponse
//   POST /v1/models/{name}:matrix            MatrixRequest       -> MatrixBlock (merged)
//   POST /v1/models/{name}:expmap            ExpMapRequest       -> ExpMapChunk (merged)
//   GET  /  and the viewer's files (WebAssetNames)
//
// The model's name comes from the path; a POST body is the request message
// without it (a body naming another model is INVALID_ARGUMENT; it may set
// model.version). GETs take ?version=N (0 or absent: the newest). An empty
// POST body is the empty message.
//
// Server-streaming calls are gathered and answered as ONE message of the
// stream's type holding every chunk: repeated fields concatenated in order,
// offsets 0, counts the totals (MatrixBlock.rows = all rows). The chunks are
// checked to tile the whole (contiguous offsets, same totals and version);
// otherwise DATA_LOSS.
//
// Errors: HTTP status from HttpStatusFromCode (grpc-gateway's table) and the
// body {"code": <google.rpc.Code>, "message": "...", "details": []}. Bad
// JSON and unknown fields are INVALID_ARGUMENT (400); a body over the limit
// is 413, an unknown path 404 (NOT_FOUND), a known path with the wrong
// method 405 (UNIMPLEMENTED in the body), before anything is sent.
//
// Thread safety: Handle may be called concurrently from any number of
// threads (the connection must allow it, as every GeodexConnection does).

#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "geodex/client/connection.h"

namespace geodex::client::cli {

struct HttpRequest {
  std::string method;                             // "GET", "POST", ...
  std::string path;                               // percent-decoded, without the query
  std::multimap<std::string, std::string> query;  // decoded query parameters
  std::string body;
};

struct HttpResponse {
  int status = 200;
  std::string content_type;
  std::string body;
};

// The HTTP status grpc-gateway answers for a gRPC code: OK 200, CANCELLED
// 499, INVALID_ARGUMENT/FAILED_PRECONDITION/OUT_OF_RANGE 400, UNAUTHENTICATED
// 401, PERMISSION_DENIED 403, NOT_FOUND 404, ALREADY_EXISTS/ABORTED 409,
// RESOURCE_EXHAUSTED 429, UNIMPLEMENTED 501, UNAVAILABLE 503,
// DEADLINE_EXCEEDED 504, UNKNOWN/INTERNAL/DATA_LOSS (and anything else) 500.
int HttpStatusFromCode(absl::StatusCode code);

// `status` as grpc-gateway's JSON error body, with HTTP status `http_status`
// (default: HttpStatusFromCode of its code).
HttpResponse ErrorResponse(const absl::Status& status, int http_status = 0);

// `mesh` in protobuf's JSON mapping, byte for byte what MessageToJsonString
// prints with always_print_primitive_fields, several times faster (the mesh
// is the largest answer the viewer asks for: 6.5 MB for 100K vertices).
std::string MeshToJson(const v1::MeshChunk& mesh);

// A file of the viewer: its bytes and MIME type.
struct WebAsset {
  std::string content_type;
  std::string body;
};
using WebAssets = std::map<std::string, WebAsset>;  // by URL path, e.g. "/viewer.js"

// The files the viewer needs, in the assets directory: index.html,
// viewer.js, viewer.css, and three.js r111's three.min.js and
// OrbitControls.js (copied there from Debian's libjs-three by the build).
const std::vector<std::string>& WebAssetNames();

// Reads every file of WebAssetNames from `dir`. Errors: NOT_FOUND naming
// the first missing file.
absl::StatusOr<WebAssets> LoadWebAssets(const std::string& dir);

class WebGateway {
 public:
  // `connection` must not be null. Bodies over `max_body_bytes` are 413.
  WebGateway(std::shared_ptr<GeodexConnection> connection, WebAssets assets, size_t max_body_bytes);

  // Answers one request. Never throws.
  HttpResponse Handle(const HttpRequest& request) const;

  size_t max_body_bytes() const { return max_body_bytes_; }

 private:
  HttpResponse HandleApi(const HttpRequest& request) const;

  std::shared_ptr<GeodexConnection> connection_;
  WebAssets assets_;
  size_t max_body_bytes_;
};

}  // namespace geodex::client::cli
