#include "client/cli/web/web_gateway.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <sstream>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "client/cli/outputs.h"
#include "google/protobuf/util/json_util.h"

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

absl::StatusOr<v1::ExpMapChunk> MergeExpMap(const std::vector<v1::ExpMapChunk>& in) {
  v1::ExpMapChunk out;
  if (in.empty()) return out;
  out.set_num_vertices(in[0].num_vertices());
  out.set_version(in[0].version());
  for (const v1::ExpMapChunk& c : in) {
    if (c.num_vertices() != out.num_vertices() || c.version() != out.version()) {
      return DataLoss("exponential map", "disagree on the count or the version");
    }
    const int n = c.vertices_size();
    if (c.r_size() != n || c.theta_size() != n || c.u_size() != n || c.v_size() != n) {
      return DataLoss("exponential map", "have arrays of different lengths");
    }
    out.mutable_vertices()->MergeFrom(c.vertices());
    out.mutable_r()->MergeFrom(c.r());
    out.mutable_theta()->MergeFrom(c.theta());
    out.mutable_u()->MergeFrom(c.u());
    out.mutable_v()->MergeFrom(c.v());
  }
  if (out.vertices_size() != out.num_vertices()) {
    return DataLoss("exponential map", "do not add up to its count");
  }
  return out;
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

}  // namespace

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

  if (verb == "distance" || verb == "path" || verb == "field" || verb == "locate" ||
      verb == "matrix" || verb == "expmap") {
    if (request.method != "POST") return wrong_method("POST");
  }
  if (verb == "distance") {
    auto r = PostRequest<v1::DistanceRequest>(name, request);
    if (!r.ok()) return ErrorResponse(r.status());
    return Answer(connection_->Distance(*r));
  }
  if (verb == "path") {
    auto r = PostRequest<v1::PathRequest>(name, request);
    if (!r.ok()) return ErrorResponse(r.status());
    return Answer(connection_->Path(*r));
  }
  if (verb == "locate") {
    auto r = PostRequest<v1::LocateRequest>(name, request);
    if (!r.ok()) return ErrorResponse(r.status());
    return Answer(connection_->Locate(*r));
  }
  if (verb == "field") {
    auto r = PostRequest<v1::DistanceFieldRequest>(name, request);
    if (!r.ok()) return ErrorResponse(r.status());
    auto chunks = connection_->DistanceField(*r);
    if (!chunks.ok()) return ErrorResponse(chunks.status());
    return Answer(MergeField(*chunks, r->with_nearest_source(), r->radius() != 0));
  }
  if (verb == "matrix") {
    auto r = PostRequest<v1::MatrixRequest>(name, request);
    if (!r.ok()) return ErrorResponse(r.status());
    auto blocks = connection_->Matrix(*r);
    if (!blocks.ok()) return ErrorResponse(blocks.status());
    return Answer(MergeMatrix(*blocks, r->error_bounds()));
  }
  if (verb == "expmap") {
    auto r = PostRequest<v1::ExpMapRequest>(name, request);
    if (!r.ok()) return ErrorResponse(r.status());
    auto chunks = connection_->ExpMap(*r);
    if (!chunks.ok()) return ErrorResponse(chunks.status());
    return Answer(MergeExpMap(*chunks));
  }
  return ErrorResponse(absl::NotFoundError(absl::StrCat("no such method: ", verb)));
}

}  // namespace geodex::client::cli
