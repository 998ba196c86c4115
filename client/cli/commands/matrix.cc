// `geodex matrix`: all sources x targets distances, one row per source.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct MatrixFlags {
  ConnectionFlags conn;
  ModelFlags model;
  std::string sources, targets, out = "-";
  NearPairs near_pairs = NearPairs::kModelDefault;
};

absl::Status Matrix(const MatrixFlags& flags) {
  absl::StatusOr<Client> client = MakeClient(flags.conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<std::vector<SurfacePoint>> sources =
      LoadPoints(*client, flags.model.ref(), flags.sources);
  if (!sources.ok()) return sources.status();
  absl::StatusOr<std::vector<SurfacePoint>> targets =
      LoadPoints(*client, flags.model.ref(), flags.targets);
  if (!targets.ok()) return targets.status();
  absl::StatusOr<DistanceMatrix> matrix =
      client->Matrix(flags.model.ref(), *sources, *targets, flags.near_pairs);
  if (!matrix.ok()) return matrix.status();
  std::string out;
  for (int64_t r = 0; r < matrix->rows; ++r) {
    for (int64_t c = 0; c < matrix->cols; ++c) {
      absl::StrAppend(&out, c ? " " : "", FormatDistance(matrix->At(r, c)));
    }
    out += "\n";
  }
  return WriteFileOrStdout(flags.out, out);
}

}  // namespace

void AddMatrixCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<MatrixFlags>();
  CLI::App* matrix =
      app->add_subcommand("matrix", "All sources x targets distances, one row per source");
  AddConnectionFlags(matrix, &flags->conn);
  AddModelFlags(matrix, &flags->model);
  matrix->add_option("--sources", flags->sources, "File of lines 'f w0 w1 w2'")->required();
  matrix->add_option("--targets", flags->targets, "File of lines 'f w0 w1 w2'")->required();
  AddNearPairsFlags(matrix, &flags->near_pairs);
  matrix->add_option("-o,--out", flags->out, "Output file ('-': standard output)");
  matrix->callback([flags, status] { *status = Matrix(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(80, AddMatrixCommand);

}  // namespace geodex::client::cli
