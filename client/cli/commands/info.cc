// `geodex info`: one model and its build report, for a person (the layout of
// `geodex-query --info`) or, with --format json, as the JSON object scripts
// read (ModelToJson: ModelInfo's fields, the build report's key/values, and
// the report's JSON as "report").

#include <memory>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/model_report.h"
#include "client/cli/outputs.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct InfoFlags {
  ConnectionFlags conn;
  ModelFlags model;
  std::string format = "text";
};

absl::Status Info(const InfoFlags& flags) {
  absl::StatusOr<Client> client = MakeClient(flags.conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<ModelInfo> info = client->GetModel(flags.model.ref());
  if (!info.ok()) return info.status();
  if (flags.format == "json") return WriteFileOrStdout("-", ModelToJson(*info));
  absl::StatusOr<std::string> text = ModelReportText(*info);
  if (!text.ok()) return text.status();
  return WriteFileOrStdout("-", *text);
}

}  // namespace

void AddInfoCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<InfoFlags>();
  CLI::App* info = app->add_subcommand(
      "info", "Describe one model: its build report (mesh, size, error target, accuracy)");
  AddConnectionFlags(info, &flags->conn);
  AddModelFlags(info, &flags->model);
  info->add_option("--format", flags->format,
                   "text (for a person, default) or json (ModelInfo's fields and the report)")
      ->check(CLI::IsMember({"text", "json"}));
  info->callback([flags, status] { *status = Info(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(20, AddInfoCommand);

}  // namespace geodex::client::cli
