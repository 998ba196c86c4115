// `geodex path`: geodesic paths of point pairs as polylines (OBJ, PLY or JSON).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/outputs.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct PathFlags {
  ConnectionFlags conn;
  ModelFlags model;
  std::string pairs, format, out = "-";
  bool xyz = false;
  uint32_t exact_corridor = 0;
};

absl::Status Path(const PathFlags& flags) {
  std::string format = flags.format;
  if (format.empty()) {
    for (const char* f : {"obj", "ply", "json"}) {
      if (absl::EndsWithIgnoreCase(flags.out, absl::StrCat(".", f))) format = f;
    }
    if (format.empty()) format = "json";
  }
  absl::StatusOr<Client> client = MakeClient(flags.conn);
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

}  // namespace

void AddPathCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<PathFlags>();
  CLI::App* path = app->add_subcommand("path", "Geodesic paths of point pairs as polylines");
  AddConnectionFlags(path, &flags->conn);
  AddModelFlags(path, &flags->model);
  path->add_option("--pairs", flags->pairs,
                   "File of lines 'fa a0 a1 a2 fb b0 b1 b2' ('-': standard input)")
      ->required();
  path->add_flag("--xyz", flags->xyz, "Lines are 'xa ya za xb yb zb' (located first)");
  path->add_option("--exact-corridor", flags->exact_corridor,
                   "Also solve each path exactly within this many edge steps of the traced one "
                   "(not O(k); 0: the model's default)")
      ->check(CLI::Range(0, 64));
  path->add_option("--format", flags->format,
                   "obj (polylines), ply (vertices and edges) or json (surface points and "
                   "positions); default: from --out's extension, else json")
      ->check(CLI::IsMember({"obj", "ply", "json"}));
  path->add_option("-o,--out", flags->out, "Output file ('-': standard output)");
  path->callback([flags, status] { *status = Path(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(40, AddPathCommand);

}  // namespace geodex::client::cli
