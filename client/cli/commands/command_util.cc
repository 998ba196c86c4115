#include "client/cli/commands/command_util.h"

#include <cstdlib>
#include <map>
#include <utility>

#include "absl/strings/cord.h"
#include "absl/strings/strip.h"
#include "absl/time/time.h"

namespace geodex::client::cli {
namespace {

constexpr char kInputErrorPayload[] = "type.geodex.dev/cli.InputError";

}  // namespace

absl::Status InputError(absl::Status status) {
  status.SetPayload(kInputErrorPayload, absl::Cord("1"));
  return status;
}

bool IsInputError(const absl::Status& status) {
  return status.GetPayload(kInputErrorPayload).has_value();
}

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

absl::StatusOr<Client> MakeClient(const ConnectionFlags& flags, int batch_size) {
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

void AddModelFlags(CLI::App* app, ModelFlags* flags) {
  app->add_option("-m,--model", flags->name, "Model name")->required();
  app->add_option("--model-version", flags->version, "Model version (0: the newest)")
      ->check(CLI::NonNegativeNumber);
}

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

}  // namespace geodex::client::cli
