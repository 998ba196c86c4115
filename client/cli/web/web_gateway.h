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
//   POST /v1/models/{name}:<verb>            the call's request  -> its answer (chunks merged)
//   GET  /  and the viewer's files (WebAssetNames)
//
// The POST routes are every other call of GEODEX_CLIENT_RPCS
// (geodex/client/connection.h), <verb> being PostVerb of its name: e.g.
// :distance (DistanceRequest -> DistanceResponse), :path, :locate, :matrix
// (MatrixRequest -> MatrixBlock, merged) and :field (DistanceFieldRequest ->
// DistanceFieldChunk, merged). A call added to that list has its route.
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
// otherwise DATA_LOSS. Matrix blocks, field chunks and mesh chunks have
// checks of their own; other streams' chunks follow MergeChunks.
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
#include "absl/strings/string_view.h"
#include "geodex/client/connection.h"
#include "google/protobuf/message.h"

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

// The verb of a call's POST route: its name in lower case ("Distance" ->
// "distance"), but "field" for DistanceField.
std::string PostVerb(absl::string_view rpc);

// The calls of GEODEX_CLIENT_RPCS that have a POST route (all but those with
// a GET route: ListModels, GetModel, GetMesh, GetTriangulation), by name.
std::vector<std::string> PostRpcs();

// Merges the chunks of a server stream into `out` (of the chunks' type), by
// the generic rule: each chunk's repeated fields are parallel arrays of one
// length, concatenated in order; every other field (the totals, the
// version) is the same in every chunk; and a singular integer field named
// num_* counts the merged entries. No chunks: `out` cleared. Errors:
// DATA_LOSS naming the rule a chunk breaks.
absl::Status MergeChunks(const std::vector<const google::protobuf::Message*>& chunks,
                         google::protobuf::Message* out);

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
