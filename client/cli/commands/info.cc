// `geodex info`: one model described as JSON, with its build report.

#include <memory>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/outputs.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct InfoFlags {
  ConnectionFlags conn;
  ModelFlags model;
};

absl::Status Info(const InfoFlags& flags) {
  absl::StatusOr<Client> client = MakeClient(flags.conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<ModelInfo> info = client->GetModel(flags.model.ref());
  if (!info.ok()) return info.status();
  return WriteFileOrStdout("-", ModelToJson(*info));
}

}  // namespace

void AddInfoCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<InfoFlags>();
  CLI::App* info = app->add_subcommand("info", "Describe one model (JSON, with its build report)");
  AddConnectionFlags(info, &flags->conn);
  AddModelFlags(info, &flags->model);
  info->callback([flags, status] { *status = Info(*flags); });
}

}  // namespace geodex::client::cli
