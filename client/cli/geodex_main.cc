// geodex: the command-line client of a geodex server.
//
//   geodex models                                   models the server knows
//   geodex info --model M                           one model, with its build report
//   geodex distance --model M --pairs FILE|- [--xyz] [--near-pairs MODE] [--tolerance X]
//                   [--error-bounds]
//   geodex path --model M --pairs FILE --format obj|ply|json --out F
//   geodex field --model M --sources FILE --out field.txt|field.ply
//   geodex locate --model M --points FILE
//   geodex expmap --model M --center "F W0 W1 W2" --radius R [--direction X Y Z]
//                 [--out decal.obj|map.txt] [--image IMG] [--png view.png]
//   geodex matrix --model M --sources FILE --targets FILE [--near-pairs MODE]
//   geodex bench --model M --concurrency C --duration S --batch B
//   geodex web --listen HOST:PORT [--assets DIR]   the viewer and an HTTP/JSON gateway
//
// Every subcommand takes --server ADDR (default $GEODEX_SERVER, else
// localhost:50051), --tls-ca/--tls-cert/--tls-key, --token/--token-file and
// --timeout. Input lines are those of geodex-query (client/cli/text_io.h).
// Results go to standard output (or --out), errors to standard error.
//
// `field --out X.ply` asks for the distance field, then for the mesh of the
// version that answered it (GetMesh pinned to that version, so that both
// come from the same index even if the model is reloaded in between), and
// writes the mesh colored by distance with the distance as the vertex
// quality; unreachable vertices are gray with quality -1 (FieldToPly in
// client/cli/outputs.h).
//
// `expmap` asks for the exponential map round the centre, then for the mesh
// of the version that answered it. --out X.obj writes the patch of faces
// inside the radius with texture coordinates (X.mtl beside it, and a
// checkerboard X_checker.png unless --image names the picture to apply, which is
// copied beside the OBJ); any other --out gets lines "vertex u v". --png
// renders the decal on the whole mesh (client/cli/render.h).
//
// Exit codes: 0 success; 2 bad usage or bad input, found before anything was
// asked of the server (unreadable or malformed file, with its line number;
// a face id past the model's end; weights that are not barycentric); 1 any
// error from the server or the network (NOT_FOUND for an unknown model,
// UNAVAILABLE, ...) and local I/O errors on output.

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/strings/cord.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/strip.h"
#include "client/cli/bench.h"
#include "client/cli/decal.h"
#include "client/cli/image.h"
#include "client/cli/outputs.h"
#include "client/cli/render.h"
#include "client/cli/text_io.h"
#include "client/cli/web/web_gateway.h"
#include "client/cli/web/web_server.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

constexpr char kInputErrorPayload[] = "type.geodex.dev/cli.InputError";

// Marks `status` as the user's input being wrong (exit code 2).
absl::Status InputError(absl::Status status) {
  status.SetPayload(kInputErrorPayload, absl::Cord("1"));
  return status;
}

bool IsInputError(const absl::Status& status) {
  return status.GetPayload(kInputErrorPayload).has_value();
}

// Flags every subcommand has.
struct ConnectionFlags {
  std::string server;
  std::string tls_ca, tls_cert, tls_key, tls_server_name;
  std::string token, token_file;
  double timeout_s = 60;
  int attempts = 4;
};

void AddConnectionFlags(CLI::App* app, ConnectionFlags* flags) {
  const char* env = std::getenv("GEODEX_SERVER");
  flags->server = env != nullptr && *env != '\0' ? env : "localhost:50051";
  app->add_option("--server", flags->server,
                  "Server address: host:port, dns:///name:port, or a list ip:port,ip:port "
                  "(default $GEODEX_SERVER, else localhost:50051)")
      ->capture_default_str();
  app->add_option("--tls-ca", flags->tls_ca, "PEM CA certificates to verify the server (TLS)");
  app->add_option("--tls-cert", flags->tls_cert, "PEM client certificate (mutual TLS)");
  app->add_option("--tls-key", flags->tls_key, "PEM client private key (mutual TLS)");
  app->add_option("--tls-server-name", flags->tls_server_name,
                  "Name to check the server's certificate against (default: from --server)");
  auto* token = app->add_option("--token", flags->token,
                                "Bearer token sent as 'authorization: Bearer TOKEN'");
  app->add_option("--token-file", flags->token_file, "File holding the bearer token")
      ->excludes(token);
  app->add_option("--timeout", flags->timeout_s, "Deadline of each call, seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--attempts", flags->attempts,
                  "Tries per call when the server is unavailable (1: no retries)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
}

absl::StatusOr<Client> MakeClient(const ConnectionFlags& flags, int batch_size = 0) {
  ConnectOptions options;
  options.tls.ca_file = flags.tls_ca;
  options.tls.cert_file = flags.tls_cert;
  options.tls.key_file = flags.tls_key;
  options.tls.server_name = flags.tls_server_name;
  options.tls.enabled = !flags.tls_server_name.empty();
  options.bearer_token = flags.token;
  if (!flags.token_file.empty()) {
    absl::StatusOr<std::string> token = ReadFileOrStdin(flags.token_file);
    if (!token.ok()) return InputError(token.status());
    options.bearer_token = std::string(absl::StripAsciiWhitespace(*token));
  }
  options.deadline = absl::Seconds(flags.timeout_s);
  options.retry.max_attempts = flags.attempts;
  if (batch_size > 0) options.batch_size = batch_size;
  absl::StatusOr<Client> client = Connect(flags.server, options);
  // Everything Connect rejects comes from the command line.
  if (!client.ok()) return InputError(client.status());
  return client;
}

// Reads and parses an input file; every failure is an input error.
template <typename Parsed>
absl::StatusOr<Parsed> ReadInput(const std::string& path,
                                 absl::StatusOr<Parsed> (*parse)(std::string_view)) {
  absl::StatusOr<std::string> text = ReadFileOrStdin(path);
  if (!text.ok()) return InputError(text.status());
  absl::StatusOr<Parsed> parsed = parse(*text);
  if (!parsed.ok()) {
    return InputError(absl::Status(
        parsed.status().code(),
        absl::StrCat(path == "-" ? "<stdin>" : path, ": ", parsed.status().message())));
  }
  return parsed;
}

// The model's face count, for checking points before sending them; 0 when
// the server does not know it yet (a model still loading), and then the
// server checks the points.
absl::StatusOr<int64_t> NumFaces(const Client& client, const ModelRef& model) {
  absl::StatusOr<ModelInfo> info = client.GetModel(model);
  if (!info.ok()) return info.status();
  return info->state == ModelInfo::State::kServing ? info->num_faces : 0;
}

absl::Status CheckPoints(const std::string& path, const std::vector<SurfacePoint>& points,
                         const std::vector<int64_t>& lines, int64_t num_faces) {
  if (num_faces <= 0) return absl::OkStatus();
  for (size_t i = 0; i < points.size(); ++i) {
    if (absl::Status s = CheckPoint(points[i], num_faces, lines[i]); !s.ok()) {
      return InputError(
          absl::Status(s.code(), absl::StrCat(path == "-" ? "<stdin>" : path, ": ", s.message())));
    }
  }
  return absl::OkStatus();
}

// Pairs from `path`: surface points, or with `xyz` 3D positions located first.
absl::StatusOr<std::vector<PointPair>> LoadPairs(const Client& client, const ModelRef& model,
                                                 const std::string& path, bool xyz) {
  if (xyz) {
    absl::StatusOr<ParsedPositionPairs> parsed = ReadInput(path, &ParsePositionPairs);
    if (!parsed.ok()) return parsed.status();
    std::vector<Position> positions = parsed->a;
    positions.insert(positions.end(), parsed->b.begin(), parsed->b.end());
    absl::StatusOr<std::vector<LocatedPoint>> located = client.Locate(model, positions);
    if (!located.ok()) return located.status();
    const size_t n = parsed->a.size();
    std::vector<PointPair> pairs(n);
    for (size_t i = 0; i < n; ++i) pairs[i] = {(*located)[i].point, (*located)[n + i].point};
    return pairs;
  }
  absl::StatusOr<ParsedPairs> parsed = ReadInput(path, &ParsePairs);
  if (!parsed.ok()) return parsed.status();
  if (parsed->pairs.empty()) return std::vector<PointPair>{};
  absl::StatusOr<int64_t> num_faces = NumFaces(client, model);
  if (!num_faces.ok()) return num_faces.status();
  for (size_t i = 0; i < parsed->pairs.size(); ++i) {
    for (const SurfacePoint* p : {&parsed->pairs[i].a, &parsed->pairs[i].b}) {
      if (absl::Status s = CheckPoints(path, {*p}, {parsed->lines[i]}, *num_faces); !s.ok()) {
        return s;
      }
    }
  }
  return std::move(parsed->pairs);
}

absl::StatusOr<std::vector<SurfacePoint>> LoadPoints(const Client& client, const ModelRef& model,
                                                     const std::string& path) {
  absl::StatusOr<ParsedPoints> parsed = ReadInput(path, &ParsePoints);
  if (!parsed.ok()) return parsed.status();
  if (parsed->points.empty()) return std::vector<SurfacePoint>{};
  absl::StatusOr<int64_t> num_faces = NumFaces(client, model);
  if (!num_faces.ok()) return num_faces.status();
  if (absl::Status s = CheckPoints(path, parsed->points, parsed->lines, *num_faces); !s.ok()) {
    return s;
  }
  return std::move(parsed->points);
}

struct ModelFlags {
  std::string name;
  int64_t version = 0;
  ModelRef ref() const { return ModelRef(name, version); }
};

// --near-pairs model|path|unfold|exact, and --exact-near-pairs for exact.
void AddNearPairsFlags(CLI::App* app, NearPairs* mode) {
  static const std::map<std::string, NearPairs> kModes = {{"model", NearPairs::kModelDefault},
                                                          {"path", NearPairs::kPath},
                                                          {"unfold", NearPairs::kUnfold},
                                                          {"exact", NearPairs::kExact}};
  CLI::Option* option =
      app->add_option_function<std::string>(
             "--near-pairs", [mode](const std::string& name) { *mode = kModes.at(name); },
             "Pairs in the same or adjacent geodesic triangles: model (the model's "
             "configuration, default), path (the traced path's length), unfold (pure O(1)) or "
             "exact (local exact propagation)")
          ->check(CLI::IsMember(kModes));
  app->add_flag_callback(
         "--exact-near-pairs", [mode] { *mode = NearPairs::kExact; }, "Same as --near-pairs exact")
      ->excludes(option);
}

void AddModelFlags(CLI::App* app, ModelFlags* flags) {
  app->add_option("-m,--model", flags->name, "Model name")->required();
  app->add_option("--model-version", flags->version, "Model version (0: the newest)")
      ->check(CLI::NonNegativeNumber);
}

// --- subcommands ---------------------------------------------------------------

absl::Status Models(const ConnectionFlags& conn, bool json) {
  absl::StatusOr<Client> client = MakeClient(conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<std::vector<ModelInfo>> models = client->ListModels();
  if (!models.ok()) return models.status();
  if (!json) return WriteFileOrStdout("-", ModelsTable(*models));
  std::string out = "[\n";
  for (size_t i = 0; i < models->size(); ++i) {
    absl::StrAppend(&out, ModelToJson((*models)[i]), i + 1 < models->size() ? ",\n" : "");
  }
  return WriteFileOrStdout("-", out + "]\n");
}

absl::Status Info(const ConnectionFlags& conn, const ModelFlags& model) {
  absl::StatusOr<Client> client = MakeClient(conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<ModelInfo> info = client->GetModel(model.ref());
  if (!info.ok()) return info.status();
  return WriteFileOrStdout("-", ModelToJson(*info));
}

struct DistanceFlags {
  ModelFlags model;
  std::string pairs, out = "-";
  bool xyz = false;
  DistanceQuery query;
  int batch = 4096;
};

absl::Status Distance(const ConnectionFlags& conn, const DistanceFlags& flags) {
  absl::StatusOr<Client> client = MakeClient(conn, flags.batch);
  if (!client.ok()) return client.status();
  absl::StatusOr<std::vector<PointPair>> pairs =
      LoadPairs(*client, flags.model.ref(), flags.pairs, flags.xyz);
  if (!pairs.ok()) return pairs.status();
  absl::StatusOr<Distances> d = client->Distance(flags.model.ref(), *pairs, flags.query);
  if (!d.ok()) return d.status();
  std::string out;
  out.reserve(d->distance.size() * 20);
  for (size_t i = 0; i < d->distance.size(); ++i) {
    absl::StrAppend(&out, FormatDistance(d->distance[i]));
    if (flags.query.error_bounds) absl::StrAppend(&out, " ", FormatDistance(d->bound[i]));
    absl::StrAppend(&out, "\n");
  }
  return WriteFileOrStdout(flags.out, out);
}

struct PathFlags {
  ModelFlags model;
  std::string pairs, format, out = "-";
  bool xyz = false;
  uint32_t exact_corridor = 0;
};

absl::Status Path(const ConnectionFlags& conn, const PathFlags& flags) {
  std::string format = flags.format;
  if (format.empty()) {
    for (const char* f : {"obj", "ply", "json"}) {
      if (absl::EndsWithIgnoreCase(flags.out, absl::StrCat(".", f))) format = f;
    }
    if (format.empty()) format = "json";
  }
  absl::StatusOr<Client> client = MakeClient(conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<std::vector<PointPair>> pairs =
      LoadPairs(*client, flags.model.ref(), flags.pairs, flags.xyz);
  if (!pairs.ok()) return pairs.status();
  absl::StatusOr<std::vector<GeodesicPath>> paths =
      client->Path(flags.model.ref(), *pairs, flags.exact_corridor);
  if (!paths.ok()) return paths.status();
  const std::string out = format == "obj"   ? PathsToObj(*paths)
                          : format == "ply" ? PathsToPly(*paths)
                                            : PathsToJson(*paths);
  return WriteFileOrStdout(flags.out, out);
}

struct FieldFlags {
  ModelFlags model;
  std::string sources, out = "-";
  bool nearest = false;
};

// The mesh the distance field `field` was computed on: GetMesh pinned to the
// version that answered the field, so that a model reloaded between the two
// calls cannot pair one version's distances with another's mesh.
absl::StatusOr<Mesh> MeshOfField(const Client& client, const ModelFlags& model,
                                 const VertexDistances& field) {
  const int64_t version = field.version != 0 ? field.version : model.version;
  absl::StatusOr<Mesh> mesh = client.GetMesh(ModelRef(model.name, version));
  if (!mesh.ok()) {
    return absl::Status(mesh.status().code(),
                        absl::StrFormat("the mesh of model '%s' version %d (the version that "
                                        "answered the distance field): %s",
                                        model.name, version, mesh.status().message()));
  }
  if (version != 0 && mesh->version != version) {
    return absl::DataLossError(absl::StrFormat(
        "the server sent the mesh of version %d for the distance field of version %d",
        mesh->version, version));
  }
  if (mesh->positions.size() != field.distances.size()) {
    return absl::DataLossError(
        absl::StrFormat("the distance field has %d vertices but the mesh of version %d has %d",
                        field.distances.size(), mesh->version, mesh->positions.size()));
  }
  return mesh;
}

absl::Status Field(const ConnectionFlags& conn, const FieldFlags& flags) {
  const bool ply = absl::EndsWithIgnoreCase(flags.out, ".ply");
  if (ply && flags.nearest) {
    return InputError(absl::InvalidArgumentError(
        "--nearest is for text output; a .ply holds the distances and colors only"));
  }
  absl::StatusOr<Client> client = MakeClient(conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<std::vector<SurfacePoint>> sources =
      LoadPoints(*client, flags.model.ref(), flags.sources);
  if (!sources.ok()) return sources.status();
  if (sources->empty()) {
    return InputError(absl::InvalidArgumentError(
        absl::StrCat(flags.sources, ": no source points (lines 'f w0 w1 w2')")));
  }
  absl::StatusOr<VertexDistances> field =
      client->DistanceField(flags.model.ref(), *sources, flags.nearest);
  if (!field.ok()) return field.status();
  if (!ply) return WriteFileOrStdout(flags.out, FieldToText(*field));
  absl::StatusOr<Mesh> mesh = MeshOfField(*client, flags.model, *field);
  if (!mesh.ok()) return mesh.status();
  return WriteFileOrStdout(flags.out, FieldToPly(*mesh, field->distances));
}

struct ExpMapFlags {
  ModelFlags model;
  std::string center, out = "-", image, png;
  std::vector<double> direction;
  ExpMapQuery query;
};

// The file name part of a path.
std::string BaseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

absl::StatusOr<std::string> ReadBinaryFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat("cannot read ", path));
  std::string contents((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return absl::DataLossError(absl::StrCat("cannot read ", path));
  return contents;
}

absl::Status ExpMapCommand(const ConnectionFlags& conn, const ExpMapFlags& flags) {
  const bool obj = absl::EndsWithIgnoreCase(flags.out, ".obj");
  if (!flags.image.empty() && !obj) {
    return InputError(absl::InvalidArgumentError("--image is for an --out X.obj decal"));
  }
  absl::StatusOr<ParsedPoints> center = ParsePoints(flags.center);
  if (!center.ok() || center->points.size() != 1) {
    return InputError(absl::InvalidArgumentError(absl::StrFormat(
        "--center wants \"F W0 W1 W2\" (a face id and three weights), got \"%s\"", flags.center)));
  }
  std::string image;
  if (!flags.image.empty()) {
    absl::StatusOr<std::string> read = ReadBinaryFile(flags.image);
    if (!read.ok()) return InputError(read.status());
    image = *std::move(read);
  }
  ExpMapQuery query = flags.query;
  if (!flags.direction.empty()) {
    query.reference_direction =
        Position{flags.direction[0], flags.direction[1], flags.direction[2]};
  }
  if (absl::Status s = CheckDecalRadius(query.radius); !s.ok()) return InputError(s);
  absl::StatusOr<Client> client = MakeClient(conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<int64_t> num_faces = NumFaces(*client, flags.model.ref());
  if (!num_faces.ok()) return num_faces.status();
  if (absl::Status s = CheckPoints("--center", center->points, {1}, *num_faces); !s.ok()) return s;
  absl::StatusOr<ExpMap> map = client->ExpMap(flags.model.ref(), center->points[0], query);
  if (!map.ok()) return map.status();
  if (!obj && flags.png.empty()) {
    std::string out;
    for (size_t i = 0; i < map->vertices.size(); ++i) {
      out += absl::StrFormat("%d %.17g %.17g\n", map->vertices[i], map->u[i], map->v[i]);
    }
    return WriteFileOrStdout(flags.out, out);
  }
  // The mesh of the version that answered the map.
  const int64_t version = map->version != 0 ? map->version : flags.model.version;
  absl::StatusOr<Mesh> mesh = client->GetMesh(ModelRef(flags.model.name, version));
  if (!mesh.ok()) return mesh.status();
  if (version != 0 && mesh->version != version) {
    return absl::DataLossError(absl::StrFormat(
        "the server sent the mesh of version %d for the exponential map of version %d",
        mesh->version, version));
  }
  if (obj) {
    const std::string stem = flags.out.substr(0, flags.out.size() - 4);
    const std::string texture =
        flags.image.empty() ? BaseName(stem) + "_checker.png" : BaseName(flags.image);
    absl::StatusOr<DecalFiles> files =
        DecalToObj(*mesh, *map, query.radius, BaseName(stem) + ".mtl", texture);
    if (!files.ok()) return files.status();
    const std::string dir = flags.out.substr(0, flags.out.size() - BaseName(flags.out).size());
    if (absl::Status s = WriteFileOrStdout(flags.out, files->obj); !s.ok()) return s;
    if (absl::Status s = WriteFileOrStdout(stem + ".mtl", files->mtl); !s.ok()) return s;
    const std::string texture_path = dir + texture;
    if (texture_path == flags.png) {
      return InputError(absl::InvalidArgumentError(
          absl::StrCat("--png ", flags.png, " would overwrite the decal's texture")));
    }
    if (flags.image.empty()) {
      if (absl::Status s = WriteFileOrStdout(texture_path, EncodePng(Checkerboard(1024, 8))); !s.ok()) {
        return s;
      }
    } else if (texture_path != flags.image) {
      if (absl::Status s = WriteFileOrStdout(texture_path, image); !s.ok()) return s;
    }
  }
  if (!flags.png.empty()) {
    absl::StatusOr<Image> picture = RenderDecal(*mesh, *map, query.radius, RenderOptions{});
    if (!picture.ok()) return picture.status();
    if (absl::Status s = WriteFileOrStdout(flags.png, EncodePng(*picture)); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status Locate(const ConnectionFlags& conn, const ModelFlags& model, const std::string& points,
                    const std::string& out_path) {
  absl::StatusOr<Client> client = MakeClient(conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<ParsedPositions> parsed = ReadInput(points, &ParsePositions);
  if (!parsed.ok()) return parsed.status();
  absl::StatusOr<std::vector<LocatedPoint>> located =
      client->Locate(model.ref(), parsed->positions);
  if (!located.ok()) return located.status();
  std::string out;
  for (const LocatedPoint& l : *located) {
    absl::StrAppendFormat(&out, "%d %.17g %.17g %.17g %.17g\n", l.point.face, l.point.w[0],
                          l.point.w[1], l.point.w[2], l.distance);
  }
  return WriteFileOrStdout(out_path, out);
}

absl::Status Matrix(const ConnectionFlags& conn, const ModelFlags& model,
                    const std::string& sources_path, const std::string& targets_path,
                    NearPairs near_pairs, const std::string& out_path) {
  absl::StatusOr<Client> client = MakeClient(conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<std::vector<SurfacePoint>> sources =
      LoadPoints(*client, model.ref(), sources_path);
  if (!sources.ok()) return sources.status();
  absl::StatusOr<std::vector<SurfacePoint>> targets =
      LoadPoints(*client, model.ref(), targets_path);
  if (!targets.ok()) return targets.status();
  absl::StatusOr<DistanceMatrix> matrix =
      client->Matrix(model.ref(), *sources, *targets, near_pairs);
  if (!matrix.ok()) return matrix.status();
  std::string out;
  for (int64_t r = 0; r < matrix->rows; ++r) {
    for (int64_t c = 0; c < matrix->cols; ++c) {
      absl::StrAppend(&out, c ? " " : "", FormatDistance(matrix->At(r, c)));
    }
    out += "\n";
  }
  return WriteFileOrStdout(out_path, out);
}

struct BenchFlags {
  ModelFlags model;
  BenchOptions options;
  double duration_s = 10, warmup_s = 1;
};

absl::Status Bench(const ConnectionFlags& conn, BenchFlags flags) {
  absl::StatusOr<Client> client = MakeClient(conn, std::max(4096, flags.options.batch));
  if (!client.ok()) return client.status();
  flags.options.model = flags.model.ref();
  flags.options.duration = absl::Seconds(flags.duration_s);
  flags.options.warmup = absl::Seconds(flags.warmup_s);
  absl::StatusOr<BenchReport> report = RunBench(*client, flags.options);
  if (!report.ok()) return report.status();
  return WriteFileOrStdout("-", FormatBenchReport(flags.options, *report));
}

struct WebFlags {
  WebServerOptions server;
  std::string assets;
  size_t max_body = 8 << 20;
};

// The viewer and the HTTP/JSON gateway (client/cli/web/web_gateway.h): a
// client of the gRPC server like any other subcommand, serving until SIGINT
// or SIGTERM. The URL goes to standard output once listening.
absl::Status Web(const ConnectionFlags& conn, WebFlags flags) {
  const std::string dir = flags.assets.empty() ? DefaultWebAssetsDir() : flags.assets;
  if (dir.empty()) {
    return InputError(absl::NotFoundError(
        "the viewer's files are not beside this binary (web/ or ../share/geodex/web/); "
        "name their directory with --assets"));
  }
  absl::StatusOr<WebAssets> assets = LoadWebAssets(dir);
  if (!assets.ok()) return InputError(assets.status());
  absl::StatusOr<Client> client = MakeClient(conn);
  if (!client.ok()) return client.status();
  const WebGateway gateway(client->connection(), *std::move(assets), flags.max_body);
  flags.server.on_listening = [&conn](const std::string& url) {
    std::printf("geodex web: serving %s (geodex server %s)\n", url.c_str(), conn.server.c_str());
    std::fflush(stdout);
  };
  absl::Status status = ServeWeb(gateway, flags.server);
  if (absl::IsInvalidArgument(status)) return InputError(status);
  return status;
}

int Main(int argc, char** argv) {
  CLI::App app{
      "geodex: geodesic distances, paths and distance fields from a geodex server.\n"
      "Exit codes: 0 ok, 2 bad usage or input (with the line), 1 server or network errors."};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Help for every subcommand");

  ConnectionFlags conn;
  absl::Status status;

  CLI::App* models = app.add_subcommand("models", "List the models the server knows");
  AddConnectionFlags(models, &conn);
  bool models_json = false;
  models->add_flag("--json", models_json, "JSON instead of a table");
  models->callback([&] { status = Models(conn, models_json); });

  CLI::App* info = app.add_subcommand("info", "Describe one model (JSON, with its build report)");
  AddConnectionFlags(info, &conn);
  ModelFlags info_model;
  AddModelFlags(info, &info_model);
  info->callback([&] { status = Info(conn, info_model); });

  CLI::App* distance = app.add_subcommand(
      "distance", "Geodesic distances of point pairs, one per line, in input order");
  AddConnectionFlags(distance, &conn);
  DistanceFlags distance_flags;
  AddModelFlags(distance, &distance_flags.model);
  distance
      ->add_option("--pairs", distance_flags.pairs,
                   "File of lines 'fa a0 a1 a2 fb b0 b1 b2' ('-': standard input)")
      ->required();
  distance->add_flag("--xyz", distance_flags.xyz,
                     "Lines are 'xa ya za xb yb zb': 3D points, located on the surface first");
  AddNearPairsFlags(distance, &distance_flags.query.near_pairs);
  distance
      ->add_option("--tolerance", distance_flags.query.tolerance,
                   "Relative error tolerance (e.g. 0.005): the server refines every pair whose "
                   "error bound exceeds tolerance x distance (0: the model's)")
      ->check(CLI::NonNegativeNumber);
  distance->add_flag("--error-bounds", distance_flags.query.error_bounds,
                     "Print 'distance bound' per line: bound = the absolute error bound");
  distance->add_option("--batch", distance_flags.batch, "Pairs per streamed batch")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  distance->add_option("-o,--out", distance_flags.out, "Output file ('-': standard output)");
  distance->callback([&] { status = Distance(conn, distance_flags); });

  CLI::App* path = app.add_subcommand("path", "Geodesic paths of point pairs as polylines");
  AddConnectionFlags(path, &conn);
  PathFlags path_flags;
  AddModelFlags(path, &path_flags.model);
  path->add_option("--pairs", path_flags.pairs,
                   "File of lines 'fa a0 a1 a2 fb b0 b1 b2' ('-': standard input)")
      ->required();
  path->add_flag("--xyz", path_flags.xyz, "Lines are 'xa ya za xb yb zb' (located first)");
  path->add_option("--exact-corridor", path_flags.exact_corridor,
                   "Also solve each path exactly within this many edge steps of the traced one "
                   "(not O(k); 0: the model's default)")
      ->check(CLI::Range(0, 64));
  path->add_option("--format", path_flags.format,
                   "obj (polylines), ply (vertices and edges) or json (surface points and "
                   "positions); default: from --out's extension, else json")
      ->check(CLI::IsMember({"obj", "ply", "json"}));
  path->add_option("-o,--out", path_flags.out, "Output file ('-': standard output)");
  path->callback([&] { status = Path(conn, path_flags); });

  CLI::App* field = app.add_subcommand(
      "field",
      "Distance from the nearest source to every mesh vertex: one line per vertex, or with "
      "--out X.ply the model's mesh colored by distance");
  AddConnectionFlags(field, &conn);
  FieldFlags field_flags;
  AddModelFlags(field, &field_flags.model);
  field->add_option("--sources", field_flags.sources, "File of lines 'f w0 w1 w2'")->required();
  field->add_flag("--nearest", field_flags.nearest,
                  "Also print the index of the nearest source on each line (text output only)");
  field
      ->add_option("-o,--out", field_flags.out,
                   "Output file ('-': standard output). Text, one distance per vertex ('inf': "
                   "unreachable); a name ending in .ply gets an ASCII PLY of the mesh (of the "
                   "version that answered) for MeshLab: per vertex x y z, a color (dark purple "
                   "at the sources to yellow at the farthest vertex) and quality = distance; "
                   "unreachable vertices are gray (128 128 128) with quality -1")
      ->capture_default_str();
  field->callback([&] { status = Field(conn, field_flags); });

  CLI::App* expmap = app.add_subcommand(
      "expmap",
      "The exponential map (geodesic polar coordinates) round a point: a textured decal "
      "(--out X.obj), lines 'vertex u v', and a rendered picture (--png)");
  AddConnectionFlags(expmap, &conn);
  ExpMapFlags expmap_flags;
  AddModelFlags(expmap, &expmap_flags.model);
  expmap->add_option("--center", expmap_flags.center, "The centre: \"F W0 W1 W2\"")->required();
  expmap->add_option("--radius", expmap_flags.query.radius, "Geodesic radius of the map")
      ->required();
  expmap
      ->add_option("--direction", expmap_flags.direction,
                   "Reference direction X Y Z (theta = 0), projected into the centre's face; "
                   "default the face's first edge")
      ->expected(3);
  AddNearPairsFlags(expmap, &expmap_flags.query.near_pairs);
  expmap->add_option("--tolerance", expmap_flags.query.tolerance,
                     "Relative error tolerance of the distances r (as for distance)");
  expmap
      ->add_option("-o,--out", expmap_flags.out,
                   "Output: X.obj writes the decal (X.obj, X.mtl and the texture X_checker.png); "
                   "anything else gets lines 'vertex u v' ('-': standard output)")
      ->capture_default_str();
  expmap->add_option("--image", expmap_flags.image,
                     "With --out X.obj: the picture to apply instead of a checkerboard (copied "
                     "beside X.obj)");
  expmap->add_option("--png", expmap_flags.png,
                     "Also render the decal on the whole mesh to this PNG (800x800)");
  expmap->callback([&] { status = ExpMapCommand(conn, expmap_flags); });

  CLI::App* locate =
      app.add_subcommand("locate", "Closest surface points of 3D positions: 'f w0 w1 w2 dist'");
  AddConnectionFlags(locate, &conn);
  ModelFlags locate_model;
  std::string locate_points, locate_out = "-";
  AddModelFlags(locate, &locate_model);
  locate->add_option("--points", locate_points, "File of lines 'x y z' ('-': standard input)")
      ->required();
  locate->add_option("-o,--out", locate_out, "Output file ('-': standard output)");
  locate->callback([&] { status = Locate(conn, locate_model, locate_points, locate_out); });

  CLI::App* matrix =
      app.add_subcommand("matrix", "All sources x targets distances, one row per source");
  AddConnectionFlags(matrix, &conn);
  ModelFlags matrix_model;
  std::string matrix_sources, matrix_targets, matrix_out = "-";
  AddModelFlags(matrix, &matrix_model);
  matrix->add_option("--sources", matrix_sources, "File of lines 'f w0 w1 w2'")->required();
  matrix->add_option("--targets", matrix_targets, "File of lines 'f w0 w1 w2'")->required();
  NearPairs matrix_near_pairs = NearPairs::kModelDefault;
  AddNearPairsFlags(matrix, &matrix_near_pairs);
  matrix->add_option("-o,--out", matrix_out, "Output file ('-': standard output)");
  matrix->callback([&] {
    status =
        Matrix(conn, matrix_model, matrix_sources, matrix_targets, matrix_near_pairs, matrix_out);
  });

  CLI::App* bench = app.add_subcommand(
      "bench", "Load generator: random pairs; prints throughput and latency percentiles");
  AddConnectionFlags(bench, &conn);
  BenchFlags bench_flags;
  AddModelFlags(bench, &bench_flags.model);
  bench->add_option("-c,--concurrency", bench_flags.options.concurrency, "Concurrent workers")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  bench->add_option("-d,--duration", bench_flags.duration_s, "Measured seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bench->add_option("--warmup", bench_flags.warmup_s, "Seconds run before measuring")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  bench->add_option("-b,--batch", bench_flags.options.batch, "Pairs per call")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  bench
      ->add_option("--mode", bench_flags.options.mode,
                   "unary: one Distance call at a time per worker; stream: --window batches in "
                   "flight per worker on a StreamDistances session")
      ->check(CLI::IsMember({"unary", "stream"}))
      ->capture_default_str();
  bench->add_option("--window", bench_flags.options.window, "Stream mode: batches in flight")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  AddNearPairsFlags(bench, &bench_flags.options.near_pairs);
  bench->add_option("--seed", bench_flags.options.seed, "Random pairs seed")->capture_default_str();
  bench->callback([&] { status = Bench(conn, bench_flags); });

  CLI::App* web = app.add_subcommand(
      "web",
      "Serve the web viewer and an HTTP/JSON gateway to this server's API (GET /v1/models, "
      "POST /v1/models/NAME:distance, ...) until interrupted");
  AddConnectionFlags(web, &conn);
  WebFlags web_flags;
  web->add_option("--listen", web_flags.server.listen,
                  "HTTP address HOST:PORT (port 0: any free port; the URL is printed). Anyone "
                  "who reaches it uses this client's token: keep it on loopback or behind a proxy")
      ->capture_default_str();
  web->add_option("--assets", web_flags.assets,
                  "Directory of the viewer's files (default: beside the binary, or the installed "
                  "share/geodex/web)");
  web->add_option("--max-body", web_flags.max_body, "Largest request body, bytes (larger: 413)")
      ->check(CLI::Range(size_t{1}, size_t{1} << 30))
      ->capture_default_str();
  web->callback([&] { status = Web(conn, web_flags); });

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help or the error
    return code == 0 ? 0 : 2;
  }
  if (status.ok()) return 0;
  std::fprintf(stderr, "geodex: %s: %s\n", absl::StatusCodeToString(status.code()).c_str(),
               std::string(status.message()).c_str());
  return IsInputError(status) ? 2 : 1;
}

}  // namespace
}  // namespace geodex::client::cli

int main(int argc, char** argv) { return geodex::client::cli::Main(argc, argv); }
