#pragma once

// What the verbs of the `geodex` command line share: the connection, model
// and --near-pairs flags, the client made from them, and the reading and
// checking of input files, whose every failure is an input error (exit 2).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {

// Marks `status` as the user's input being wrong (exit code 2), as opposed to
// an error of the server, the network or local output (exit code 1).
absl::Status InputError(absl::Status status);

// Whether `status` was marked by InputError.
bool IsInputError(const absl::Status& status);

// Flags every subcommand has: where the server is and how to reach it.
struct ConnectionFlags {
  std::string server;
  std::string tls_ca, tls_cert, tls_key, tls_server_name;
  std::string token, token_file;
  double timeout_s = 60;
  int attempts = 4;
};

// Adds --server (default $GEODEX_SERVER, else localhost:50051), the TLS and
// token flags, --timeout and --attempts to `app`, bound to `flags`.
void AddConnectionFlags(CLI::App* app, ConnectionFlags* flags);

// A client connected as `flags` say, with `batch_size` pairs per streamed
// batch (0: the client's default). Errors, all input errors: an unreadable
// --token-file, and whatever Connect rejects (it comes from the command line).
absl::StatusOr<Client> MakeClient(const ConnectionFlags& flags, int batch_size = 0);

// The model a verb asks about: -m,--model (required) and --model-version
// (0: the newest), added by AddModelFlags.
struct ModelFlags {
  std::string name;
  int64_t version = 0;
  ModelRef ref() const { return ModelRef(name, version); }
};
void AddModelFlags(CLI::App* app, ModelFlags* flags);

// --near-pairs model|path|unfold|exact, and --exact-near-pairs for exact.
void AddNearPairsFlags(CLI::App* app, NearPairs* mode);

// Reads and parses an input file ('-': standard input); every failure is an
// input error, a parse error prefixed with the file's name.
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
// server checks the points. Errors: GetModel's.
absl::StatusOr<int64_t> NumFaces(const Client& client, const ModelRef& model);

// Checks `points`, read from `path` at `lines`, against a model of
// `num_faces` faces (CheckPoint); nothing is checked when num_faces <= 0.
// Errors: input errors naming `path` and the line.
absl::Status CheckPoints(const std::string& path, const std::vector<SurfacePoint>& points,
                         const std::vector<int64_t>& lines, int64_t num_faces);

// Pairs from `path`: surface points, checked against the model, or with
// `xyz` 3D positions located first. Errors: ReadInput's, CheckPoints', and
// the server's (GetModel, Locate).
absl::StatusOr<std::vector<PointPair>> LoadPairs(const Client& client, const ModelRef& model,
                                                 const std::string& path, bool xyz);

// Surface points "f w0 w1 w2" from `path`, checked against the model.
// Errors: as LoadPairs.
absl::StatusOr<std::vector<SurfacePoint>> LoadPoints(const Client& client, const ModelRef& model,
                                                     const std::string& path);

}  // namespace geodex::client::cli
