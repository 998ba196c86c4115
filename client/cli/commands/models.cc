// `geodex models`: the models the server knows, as a table or JSON.

#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/outputs.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct ModelsFlags {
  ConnectionFlags conn;
  bool json = false;
};

absl::Status Models(const ModelsFlags& flags) {
  absl::StatusOr<Client> client = MakeClient(flags.conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<std::vector<ModelInfo>> models = client->ListModels();
  if (!models.ok()) return models.status();
  if (!flags.json) return WriteFileOrStdout("-", ModelsTable(*models));
  std::string out = "[\n";
  for (size_t i = 0; i < models->size(); ++i) {
    absl::StrAppend(&out, ModelToJson((*models)[i]), i + 1 < models->size() ? ",\n" : "");
  }
  return WriteFileOrStdout("-", out + "]\n");
}

}  // namespace

void AddModelsCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<ModelsFlags>();
  CLI::App* models = app->add_subcommand("models", "List the models the server knows");
  AddConnectionFlags(models, &flags->conn);
  models->add_flag("--json", flags->json, "JSON instead of a table");
  models->callback([flags, status] { *status = Models(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(10, AddModelsCommand);

}  // namespace geodex::client::cli
