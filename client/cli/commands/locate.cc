// `geodex locate`: the closest surface point of each 3D position, one line
// "f w0 w1 w2 dist" per position.

#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct LocateFlags {
  ConnectionFlags conn;
  ModelFlags model;
  std::string points, out = "-";
};

absl::Status Locate(const LocateFlags& flags) {
  absl::StatusOr<Client> client = MakeClient(flags.conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<ParsedPositions> parsed = ReadInput(flags.points, &ParsePositions);
  if (!parsed.ok()) return parsed.status();
  absl::StatusOr<std::vector<LocatedPoint>> located =
      client->Locate(flags.model.ref(), parsed->positions);
  if (!located.ok()) return located.status();
  std::string out;
  for (const LocatedPoint& l : *located) {
    absl::StrAppendFormat(&out, "%d %.17g %.17g %.17g %.17g\n", l.point.face, l.point.w[0],
                          l.point.w[1], l.point.w[2], l.distance);
  }
  return WriteFileOrStdout(flags.out, out);
}

}  // namespace

void AddLocateCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<LocateFlags>();
  CLI::App* locate =
      app->add_subcommand("locate", "Closest surface points of 3D positions: 'f w0 w1 w2 dist'");
  AddConnectionFlags(locate, &flags->conn);
  AddModelFlags(locate, &flags->model);
  locate->add_option("--points", flags->points, "File of lines 'x y z' ('-': standard input)")
      ->required();
  locate->add_option("-o,--out", flags->out, "Output file ('-': standard output)");
  locate->callback([flags, status] { *status = Locate(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(70, AddLocateCommand);

}  // namespace geodex::client::cli
