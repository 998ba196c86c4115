#include "client/cli/web/web_gateway.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <sstream>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "client/cli/outputs.h"
#include "google/protobuf/util/json_util.h"
#include "google/protobuf/util/message_differencer.h"

namespace geodex::client::cli {
namespace {

constexpr char kJson[] = "application/json";

absl::StatusOr<std::string> ToJson(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  // As grpc-gateway v2 prints by default: every field, so that a client sees
  // a zero distance or an empty list rather than a missing key.
  options.always_print_primitive_fields = true;
  std::string out;
  const auto status = google::protobuf::util::MessageToJsonString(message, &out, options);
  if (!status.ok()) {
    return absl::InternalError(
        absl::StrCat("cannot print the answer as JSON: ", status.message().ToString()));
  }
  return out;
}

absl::Status FromJson(const std::string& body, google::protobuf::Message* message) {
  if (body.find_first_not_of(" \t\r\n") == std::string::npos) return absl::OkStatus();
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // a misspelt field must not be silently dropped
  const auto status = google::protobuf::util::JsonStringToMessage(body, message, options);
  if (!status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("the body is not a JSON ",
                                                   message->GetDescriptor()->full_name(), ": ",
                                                   status.message().ToString()));
  }
  return absl::OkStatus();
}

HttpResponse JsonResponse(const absl::StatusOr<std::string>& json) {
  if (!json.ok()) return ErrorResponse(json.status());
  return {200, kJson, *json};
}

template <class Message>
HttpResponse Answer(const absl::StatusOr<Message>& answer) {
  if (!answer.ok()) return ErrorResponse(answer.status());
  return JsonResponse(ToJson(*answer));
}

absl::Status DataLoss(absl::string_view what, absl::string_view detail) {
  return absl::DataLossError(absl::StrCat("the server's ", what, " chunks ", detail));
}

// A double as protobuf's JSON printer writes it (3.21: SimpleDtoa, the
// shortest of %.15g and %.17g that reads back exactly; non-finite values as
// strings).
void AppendJsonDouble(double x, std::string* out) {
  if (std::isnan(x)) {
    out->append("\"NaN\"");
    return;
  }
  if (std::isinf(x)) {
    out->append(x > 0 ? "\"Infinity\"" : "\"-Infinity\"");
    return;
  }
  char buffer[32];
  int n = std::snprintf(buffer, sizeof buffer, "%.15g", x);
  if (std::strtod(buffer, nullptr) != x) n = std::snprintf(buffer, sizeof buffer, "%.17g", x);
  out->append(buffer, n);
}

}  // namespace

std::string MeshToJson(const v1::MeshChunk& mesh) {
  std::string out;
  out.reserve(24 * mesh.positions_size() + 8 * mesh.faces_size() + 160);
  absl::StrAppend(&out, "{\"numVertices\":", mesh.num_vertices(),
                  ",\"numFaces\":", mesh.num_faces(), ",\"version\":\"", mesh.version(),
                  "\",\"vertexOffset\":", mesh.vertex_offset(), ",\"positions\":[");
  for (int i = 0; i < mesh.positions_size(); ++i) {
    if (i > 0) out.push_back(',');
    AppendJsonDouble(mesh.positions(i), &out);
  }
  absl::StrAppend(&out, "],\"faceOffset\":", mesh.face_offset(), ",\"faces\":[");
  for (int i = 0; i < mesh.faces_size(); ++i) {
    if (i > 0) out.push_back(',');
    absl::StrAppend(&out, mesh.faces(i));
  }
  out.append("]}");
  return out;
}

absl::Status MergeChunks(const std::vector<const google::protobuf::Message*>& chunks,
                         google::protobuf::Message* out) {
  out->Clear();
  if (chunks.empty()) return absl::OkStatus();
  const google::protobuf::Descriptor* type = out->GetDescriptor();
  const google::protobuf::Reflection* reflection = out->GetReflection();
  const std::string what = type->name();
  // A chunk without its arrays: what every chunk must repeat.
  auto totals = [&](const google::protobuf::Message& chunk) {
    std::unique_ptr<google::protobuf::Message> copy(chunk.New());
    copy->CopyFrom(chunk);
    for (int i = 0; i < type->field_count(); ++i) {
      if (type->field(i)->is_repeated()) reflection->ClearField(copy.get(), type->field(i));
    }
    return copy;
  };
  const std::unique_ptr<google::protobuf::Message> first = totals(*chunks[0]);
  int64_t entries = 0;
  for (const google::protobuf::Message* chunk : chunks) {
    if (chunk->GetDescriptor() != type) {
      return absl::InternalError(absl::StrCat("MergeChunks: a ", chunk->GetTypeName(),
                                              " among chunks of ", type->full_name()));
    }
    if (!google::protobuf::util::MessageDifferencer::Equals(*first, *totals(*chunk))) {
      return DataLoss(what, "disagree on their totals or the version");
    }
    int length = -1;
    for (int i = 0; i < type->field_count(); ++i) {
      const google::protobuf::FieldDescriptor* field = type->field(i);
      if (!field->is_repeated()) continue;
      const int n = reflection->FieldSize(*chunk, field);
      if (length >= 0 && n != length) return DataLoss(what, "have arrays of different lengths");
      length = n;
    }
    entries += std::max(length, 0);
    out->MergeFrom(*chunk);
  }
  for (int i = 0; i < type->field_count(); ++i) {
    const google::protobuf::FieldDescriptor* field = type->field(i);
    if (field->is_repeated() || !absl::StartsWith(field->name(), "num_")) continue;
    int64_t total = 0;
    switch (field->cpp_type()) {
      case google::protobuf::FieldDescriptor::CPPTYPE_INT32:
        total = reflection->GetInt32(*out, field);
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_INT64:
        total = reflection->GetInt64(*out, field);
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_UINT32:
        total = reflection->GetUInt32(*out, field);
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_UINT64:
        total = static_cast<int64_t>(reflection->GetUInt64(*out, field));
        break;
      default:
        continue;
    }
    if (total != entries) {
      return DataLoss(what, absl::StrCat("do not add up to its ", field->name()));
    }
  }
  return absl::OkStatus();
}

namespace {

// --- merging the chunks of a server stream into one message --------------------

// Both forms of the field: per vertex, or (with a radius) the sparse one,
// whose offsets and total count entries instead of vertices.
absl::StatusOr<v1::DistanceFieldChunk> MergeField(const std::vector<v1::DistanceFieldChunk>& in,
                                                  bool with_nearest_source, bool within_radius) {
  v1::DistanceFieldChunk out;
  if (in.empty()) return out;
  out.set_num_vertices(in[0].num_vertices());
  out.set_version(in[0].version());
  for (const v1::DistanceFieldChunk& c : in) {
    if (c.num_vertices() != out.num_vertices() || c.version() != out.version()) {
      return DataLoss("distance field", "disagree on the vertex count or the version");
    }
    if (c.vertex_offset() != out.distances_size()) {
      return DataLoss("distance field", "are not contiguous");
    }
    if (with_nearest_source && c.nearest_source_size() != c.distances_size()) {
      return DataLoss("distance field", "lack nearest sources");
    }
    if (c.vertices_size() != (within_radius ? c.distances_size() : 0)) {
      return DataLoss("distance field", "do not give one vertex per distance");
    }
    out.mutable_distances()->MergeFrom(c.distances());
    out.mutable_nearest_source()->MergeFrom(c.nearest_source());
    out.mutable_vertices()->MergeFrom(c.vertices());
  }
  if (out.distances_size() != out.num_vertices()) {
    return DataLoss("distance field", "do not cover every vertex");
  }
  return out;
}

absl::StatusOr<v1::MeshChunk> MergeMesh(const std::vector<v1::MeshChunk>& in) {
  v1::MeshChunk out;
  if (in.empty()) return out;
  out.set_num_vertices(in[0].num_vertices());
  out.set_num_faces(in[0].num_faces());
  out.set_version(in[0].version());
  for (const v1::MeshChunk& c : in) {
    if (c.num_vertices() != out.num_vertices() || c.num_faces() != out.num_faces() ||
        c.version() != out.version()) {
      return DataLoss("mesh", "disagree on the totals or the version");
    }
    if (static_cast<int64_t>(c.vertex_offset()) * 3 != out.positions_size() ||
        static_cast<int64_t>(c.face_offset()) * 3 != out.faces_size() ||
        c.positions_size() % 3 != 0 || c.faces_size() % 3 != 0) {
      return DataLoss("mesh", "are not contiguous");
    }
    out.mutable_positions()->MergeFrom(c.positions());
    out.mutable_faces()->MergeFrom(c.faces());
  }
  if (out.positions_size() != 3 * static_cast<int64_t>(out.num_vertices()) ||
      out.faces_size() != 3 * static_cast<int64_t>(out.num_faces())) {
    return DataLoss("mesh", "do not cover the whole mesh");
  }
  return out;
}

absl::StatusOr<v1::MatrixBlock> MergeMatrix(const std::vector<v1::MatrixBlock>& in,
                                            bool error_bounds) {
  v1::MatrixBlock out;
  if (in.empty()) return out;
  out.set_num_targets(in[0].num_targets());
  out.set_version(in[0].version());
  for (const v1::MatrixBlock& b : in) {
    if (b.num_targets() != out.num_targets() || b.version() != out.version()) {
      return DataLoss("matrix", "disagree on the target count or the version");
    }
    if (b.row_offset() != out.rows() || b.values_size() != b.rows() * b.num_targets() ||
        (error_bounds && b.bounds_size() != b.values_size())) {
      return DataLoss("matrix", "are not contiguous row blocks");
    }
    out.set_rows(out.rows() + b.rows());
    out.mutable_values()->MergeFrom(b.values());
    out.mutable_bounds()->MergeFrom(b.bounds());
  }
  return out;
}

// Chunks of another stream (one with no merge of its own above), by the
// generic rule of MergeChunks.
template <class Chunk>
absl::StatusOr<Chunk> MergeGeneric(const std::vector<Chunk>& in) {
  std::vector<const google::protobuf::Message*> chunks;
  chunks.reserve(in.size());
  for (const Chunk& c : in) chunks.push_back(&c);
  Chunk out;
  if (absl::Status s = MergeChunks(chunks, &out); !s.ok()) return s;
  return out;
}

// One stream's chunks merged, by the stream's request: the field's and the
// matrix's checks depend on what was asked.
absl::StatusOr<v1::DistanceFieldChunk> Merge(const v1::DistanceFieldRequest& request,
                                             const std::vector<v1::DistanceFieldChunk>& in) {
  return MergeField(in, request.with_nearest_source(), request.radius() != 0);
}
absl::StatusOr<v1::MatrixBlock> Merge(const v1::MatrixRequest& request,
                                      const std::vector<v1::MatrixBlock>& in) {
  return MergeMatrix(in, request.error_bounds());
}
template <class Request, class Chunk>
absl::StatusOr<Chunk> Merge(const Request& /*request*/, const std::vector<Chunk>& in) {
  return MergeGeneric(in);
}

// --- requests -------------------------------------------------------------------

// ?version=N of a GET. Errors: INVALID_ARGUMENT for anything but one integer.
absl::StatusOr<int64_t> VersionParameter(const HttpRequest& request) {
  int64_t version = 0;
  auto [begin, end] = request.query.equal_range("version");
  for (auto it = begin; it != end; ++it) {
    if (std::next(it) != end) {
      return absl::InvalidArgumentError("the query parameter 'version' is given twice");
    }
    if (!absl::SimpleAtoi(it->second, &version)) {
      return absl::InvalidArgumentError(
          absl::StrCat("the query parameter 'version' is not an integer: '", it->second, "'"));
    }
  }
  return version;
}

// A GET's ModelRef: the name from the path, the version from ?version=.
absl::StatusOr<v1::ModelRef> GetModelRef(const std::string& name, const HttpRequest& request) {
  for (const auto& [key, value] : request.query) {
    if (key != "version") {
      return absl::InvalidArgumentError(absl::StrCat("unknown query parameter '", key, "'"));
    }
  }
  absl::StatusOr<int64_t> version = VersionParameter(request);
  if (!version.ok()) return version.status();
  v1::ModelRef ref;
  ref.set_name(name);
  ref.set_version(*version);
  return ref;
}

// A POST's request message: the body, with the model's name from the path.
template <class Request>
absl::StatusOr<Request> PostRequest(const std::string& name, const HttpRequest& http) {
  Request request;
  if (absl::Status s = FromJson(http.body, &request); !s.ok()) return s;
  if (!request.model().name().empty() && request.model().name() != name) {
    return absl::InvalidArgumentError(absl::StrCat("the body names model '", request.model().name(),
                                                   "' but the path names '", name, "'"));
  }
  if (!http.query.empty()) {
    absl::StatusOr<v1::ModelRef> ref = GetModelRef(name, http);
    if (!ref.ok()) return ref.status();
    if (request.model().version() != 0 && ref->version() != request.model().version()) {
      return absl::InvalidArgumentError("the body and ?version= name different versions");
    }
    request.mutable_model()->set_version(ref->version());
  }
  request.mutable_model()->set_name(name);
  return request;
}

template <class T>
constexpr bool kIsStream = false;
template <class Chunk>
constexpr bool kIsStream<std::vector<Chunk>> = true;

// A POST route: the request from the body, the connection's call `kRpc`,
// and its answer (a stream's chunks merged).
template <class Request, class Result,
          absl::StatusOr<Result> (GeodexConnection::*kRpc)(const Request&)>
HttpResponse CallRpc(GeodexConnection& connection, const std::string& name,
                     const HttpRequest& http) {
  absl::StatusOr<Request> request = PostRequest<Request>(name, http);
  if (!request.ok()) return ErrorResponse(request.status());
  absl::StatusOr<Result> result = (connection.*kRpc)(*request);
  if (!result.ok()) return ErrorResponse(result.status());
  if constexpr (kIsStream<Result>) {
    return Answer(Merge(*request, *result));
  } else {
    return JsonResponse(ToJson(*result));
  }
}

// The calls with a GET route of their own (WebGateway::HandleApi), which
// have no POST route.
bool HasGetRoute(absl::string_view rpc) {
  return rpc == "ListModels" || rpc == "GetModel" || rpc == "GetMesh" || rpc == "GetTriangulation";
}

using PostHandler = HttpResponse (*)(GeodexConnection& connection, const std::string& name,
                                     const HttpRequest& http);

// Adds the POST route of call `rpc` to `routes` unless it has a GET route
// (a request naming no model, as ListModels', has one).
template <class Request, class Result,
          absl::StatusOr<Result> (GeodexConnection::*kRpc)(const Request&)>
void AddPostRoute(absl::string_view rpc, std::map<std::string, PostHandler>* routes) {
  if constexpr (requires(const Request& r) { r.model(); }) {
    if (!HasGetRoute(rpc)) (*routes)[PostVerb(rpc)] = &CallRpc<Request, Result, kRpc>;
  }
}

// The POST routes by verb, from GEODEX_CLIENT_RPCS.
const std::map<std::string, PostHandler>& PostRoutes() {
  static const auto* const routes = [] {
    auto* out = new std::map<std::string, PostHandler>;
#define GEODEX_WEB_POST_ROUTE(Name, Request, Result) \
  AddPostRoute<Request, Result, &GeodexConnection::Name>(#Name, out);
    GEODEX_CLIENT_RPCS(GEODEX_WEB_POST_ROUTE)
#undef GEODEX_WEB_POST_ROUTE
    return out;
  }();
  return *routes;
}

}  // namespace

std::string PostVerb(absl::string_view rpc) {
  // The viewer's name for DistanceField predates this rule.
  if (rpc == "DistanceField") return "field";
  return absl::AsciiStrToLower(rpc);
}

std::vector<std::string> PostRpcs() {
  std::vector<std::string> out;
#define GEODEX_WEB_POST_RPC(Name, Request, Result) \
  if (!HasGetRoute(#Name)) out.push_back(#Name);
  GEODEX_CLIENT_RPCS(GEODEX_WEB_POST_RPC)
#undef GEODEX_WEB_POST_RPC
  return out;
}

int HttpStatusFromCode(absl::StatusCode code) {
  switch (code) {
    case absl::StatusCode::kOk:
      return 200;
    case absl::StatusCode::kCancelled:
      return 499;
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kFailedPrecondition:
    case absl::StatusCode::kOutOfRange:
      return 400;
    case absl::StatusCode::kUnauthenticated:
      return 401;
    case absl::StatusCode::kPermissionDenied:
      return 403;
    case absl::StatusCode::kNotFound:
      return 404;
    case absl::StatusCode::kAlreadyExists:
    case absl::StatusCode::kAborted:
      return 409;
    case absl::StatusCode::kResourceExhausted:
      return 429;
    case absl::StatusCode::kUnimplemented:
      return 501;
    case absl::StatusCode::kUnavailable:
      return 503;
    case absl::StatusCode::kDeadlineExceeded:
      return 504;
    case absl::StatusCode::kUnknown:
    case absl::StatusCode::kInternal:
    case absl::StatusCode::kDataLoss:
    default:
      return 500;
  }
}

HttpResponse ErrorResponse(const absl::Status& status, int http_status) {
  HttpResponse out;
  out.status = http_status != 0 ? http_status : HttpStatusFromCode(status.code());
  out.content_type = kJson;
  out.body = absl::StrFormat(R"({"code":%d,"message":%s,"details":[]})",
                             static_cast<int>(status.code()),
                             JsonString(std::string(status.message())));
  return out;
}

const std::vector<std::string>& WebAssetNames() {
  static const std::vector<std::string> kNames = {
      "index.html", "viewer.js", "report_chart.js", "viewer.css", "three.min.js",
      "OrbitControls.js"};
  return kNames;
}

absl::StatusOr<WebAssets> LoadWebAssets(const std::string& dir) {
  WebAssets assets;
  for (const std::string& name : WebAssetNames()) {
    const std::string path = absl::StrCat(dir, "/", name);
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      return absl::NotFoundError(absl::StrCat("the viewer's file ", path, " is missing"));
    }
    std::ostringstream contents;
    contents << in.rdbuf();
    const std::string type = absl::EndsWith(name, ".html") ? "text/html; charset=utf-8"
                             : absl::EndsWith(name, ".css")
                                 ? "text/css; charset=utf-8"
                                 : "application/javascript; charset=utf-8";
    assets["/" + name] = {type, contents.str()};
  }
  return assets;
}

WebGateway::WebGateway(std::shared_ptr<GeodexConnection> connection, WebAssets assets,
                       size_t max_body_bytes)
    : connection_(std::move(connection)),
      assets_(std::move(assets)),
      max_body_bytes_(max_body_bytes) {}

HttpResponse WebGateway::Handle(const HttpRequest& request) const {
  // Nothing may escape into the HTTP server's threads (STYLE: exceptions
  // never cross module boundaries); protobuf and the allocator may throw.
  try {
    if (request.body.size() > max_body_bytes_) {
      return ErrorResponse(absl::ResourceExhaustedError(absl::StrFormat(
                               "the body has %d bytes; the limit is %d (--max-body)",
                               request.body.size(), max_body_bytes_)),
                           413);
    }
    if (absl::StartsWith(request.path, "/v1/")) return HandleApi(request);
    const std::string path = request.path == "/" ? "/index.html" : request.path;
    auto it = assets_.find(path);
    if (it == assets_.end()) {
      return ErrorResponse(absl::NotFoundError(absl::StrCat("no such page: ", request.path)));
    }
    if (request.method != "GET" && request.method != "HEAD") {
      return ErrorResponse(absl::UnimplementedError(
                               absl::StrCat("method ", request.method, " not allowed on ", path)),
                           405);
    }
    return {200, it->second.content_type, it->second.body};
  } catch (const std::exception& e) {
    return ErrorResponse(absl::InternalError(absl::StrCat("the gateway failed: ", e.what())));
  } catch (...) {
    return ErrorResponse(absl::InternalError("the gateway failed"));
  }
}

HttpResponse WebGateway::HandleApi(const HttpRequest& request) const {
  constexpr absl::string_view kModels = "/v1/models";
  const std::string& path = request.path;
  auto wrong_method = [&](const char* want) {
    return ErrorResponse(absl::UnimplementedError(absl::StrCat(
                             "method ", request.method, " not allowed on ", path, "; use ", want)),
                         405);
  };
  if (path == kModels) {
    if (request.method != "GET") return wrong_method("GET");
    if (!request.query.empty()) {
      return ErrorResponse(absl::InvalidArgumentError("/v1/models takes no query parameters"));
    }
    return Answer(connection_->ListModels(v1::ListModelsRequest()));
  }
  if (!absl::StartsWith(path, absl::StrCat(kModels, "/"))) {
    return ErrorResponse(absl::NotFoundError(absl::StrCat("no such API path: ", path)));
  }
  std::string rest = path.substr(kModels.size() + 1);
  std::string verb, collection;
  bool custom_method = false;  // "NAME:VERB"
  if (const size_t slash = rest.find('/'); slash != std::string::npos) {
    collection = rest.substr(slash + 1);
    rest.resize(slash);
  } else if (const size_t colon = rest.rfind(':'); colon != std::string::npos) {
    custom_method = true;
    verb = rest.substr(colon + 1);
    rest.resize(colon);
  }
  const std::string& name = rest;
  if (name.empty()) return ErrorResponse(absl::NotFoundError("the path names no model"));

  if (!custom_method) {
    if (request.method != "GET") return wrong_method("GET");
    absl::StatusOr<v1::ModelRef> ref = GetModelRef(name, request);
    if (!ref.ok()) return ErrorResponse(ref.status());
    if (collection.empty()) {
      v1::GetModelRequest get;
      *get.mutable_model() = *ref;
      return Answer(connection_->GetModel(get));
    }
    if (collection == "mesh") {
      v1::GetMeshRequest get;
      *get.mutable_model() = *ref;
      absl::StatusOr<std::vector<v1::MeshChunk>> chunks = connection_->GetMesh(get);
      if (!chunks.ok()) return ErrorResponse(chunks.status());
      absl::StatusOr<v1::MeshChunk> mesh = MergeMesh(*chunks);
      if (!mesh.ok()) return ErrorResponse(mesh.status());
      return {200, kJson, MeshToJson(*mesh)};
    }
    if (collection == "triangulation") {
      v1::GetTriangulationRequest get;
      *get.mutable_model() = *ref;
      return Answer(connection_->GetTriangulation(get));
    }
    return ErrorResponse(absl::NotFoundError(absl::StrCat("no such API path: ", path)));
  }

  const auto route = PostRoutes().find(verb);
  if (route != PostRoutes().end()) {
    if (request.method != "POST") return wrong_method("POST");
    return route->second(*connection_, name, request);
  }
  return ErrorResponse(absl::NotFoundError(absl::StrCat("no such method: ", verb)));
}

}  // namespace geodex::client::cli
