// `geodex distance`: geodesic distances of point pairs, one line per pair in
// input order ("distance", or "distance bound" with --error-bounds).

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

struct DistanceFlags {
  ConnectionFlags conn;
  ModelFlags model;
  std::string pairs, out = "-";
  bool xyz = false;
  DistanceQuery query;
  int batch = 4096;
};

absl::Status Distance(const DistanceFlags& flags) {
  absl::StatusOr<Client> client = MakeClient(flags.conn, flags.batch);
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

}  // namespace

void AddDistanceCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<DistanceFlags>();
  CLI::App* distance = app->add_subcommand(
      "distance", "Geodesic distances of point pairs, one per line, in input order");
  AddConnectionFlags(distance, &flags->conn);
  AddModelFlags(distance, &flags->model);
  distance
      ->add_option("--pairs", flags->pairs,
                   "File of lines 'fa a0 a1 a2 fb b0 b1 b2' ('-': standard input)")
      ->required();
  distance->add_flag("--xyz", flags->xyz,
                     "Lines are 'xa ya za xb yb zb': 3D points, located on the surface first");
  AddNearPairsFlags(distance, &flags->query.near_pairs);
  distance
      ->add_option("--tolerance", flags->query.tolerance,
                   "Relative error tolerance (e.g. 0.005): the server refines every pair whose "
                   "error bound exceeds tolerance x distance (0: the model's)")
      ->check(CLI::NonNegativeNumber);
  distance
      ->add_option("--refine-below", flags->query.refine_below,
                   "Refine every pair that may be closer than this many L1000, the spacing of "
                   "1,000 samples on the surface (e.g. 8: the every-distance mode; 0: the "
                   "model's threshold)")
      ->check(CLI::NonNegativeNumber);
  distance->add_flag("--error-bounds", flags->query.error_bounds,
                     "Print 'distance bound' per line: bound = the absolute error bound");
  distance->add_option("--batch", flags->batch, "Pairs per streamed batch")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  distance->add_option("-o,--out", flags->out, "Output file ('-': standard output)");
  distance->callback([flags, status] { *status = Distance(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(30, AddDistanceCommand);

}  // namespace geodex::client::cli
