// `geodex bench`: a load generator of random pairs (RunBench,
// client/cli/bench.h): uniform pairs, then near pairs 1L-3L apart; prints
// the throughput and latency percentiles of each.

#include "client/cli/bench.h"

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct BenchFlags {
  ConnectionFlags conn;
  ModelFlags model;
  BenchOptions options;
  double duration_s = 10, warmup_s = 1;
  std::string pairs = "both";
};

absl::Status Bench(BenchFlags flags) {
  absl::StatusOr<Client> client = MakeClient(flags.conn, std::max(4096, flags.options.batch));
  if (!client.ok()) return client.status();
  flags.options.model = flags.model.ref();
  flags.options.duration = absl::Seconds(flags.duration_s);
  flags.options.warmup = absl::Seconds(flags.warmup_s);
  std::string out;
  using Pairs = BenchOptions::Pairs;
  std::vector<Pairs> kinds;
  if (flags.pairs == "both" || flags.pairs == "uniform") kinds.push_back(Pairs::kUniform);
  if (flags.pairs == "area") kinds.push_back(Pairs::kArea);
  if (flags.pairs == "both" || flags.pairs == "near") kinds.push_back(Pairs::kNear);
  for (const Pairs kind : kinds) {
    BenchOptions options = flags.options;
    options.pairs = kind;
    absl::StatusOr<BenchReport> report = RunBench(*client, options);
    if (!report.ok()) return report.status();
    if (!out.empty()) out += '\n';
    out += FormatBenchReport(options, *report);
  }
  return WriteFileOrStdout("-", out);
}

}  // namespace

void AddBenchCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<BenchFlags>();
  CLI::App* bench = app->add_subcommand(
      "bench",
      "Load generator: uniform random pairs, then near pairs (1L-3L apart, L the model's sample "
      "spacing, where answers are refined); prints throughput and latency percentiles of each");
  AddConnectionFlags(bench, &flags->conn);
  AddModelFlags(bench, &flags->model);
  bench->add_option("-c,--concurrency", flags->options.concurrency, "Concurrent workers")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  bench->add_option("-d,--duration", flags->duration_s, "Measured seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bench->add_option("--warmup", flags->warmup_s, "Seconds run before measuring")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  bench->add_option("-b,--batch", flags->options.batch, "Pairs per call")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  bench
      ->add_option("--mode", flags->options.mode,
                   "unary: one Distance call at a time per worker; stream: --window batches in "
                   "flight per worker on a StreamDistances session")
      ->check(CLI::IsMember({"unary", "stream"}))
      ->capture_default_str();
  bench->add_option("--window", flags->options.window, "Stream mode: batches in flight")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  bench
      ->add_option("--pairs", flags->pairs,
                   "both: uniform pairs, then near pairs (each for --duration); uniform: pairs of "
                   "random faces, most far apart; area: area-uniform pairs, as the in-process "
                   "benchmarks draw them (reads the mesh once); near: pairs 1L-3L apart in a "
                   "straight line on one sheet of the surface (L = sqrt(2 A / (sqrt(3) m)) from "
                   "the mesh's area A and the model's m samples; reads the mesh once)")
      ->check(CLI::IsMember({"both", "uniform", "area", "near"}))
      ->capture_default_str();
  AddNearPairsFlags(bench, &flags->options.near_pairs);
  bench
      ->add_option("--refine-below", flags->options.refine_below,
                   "Refine every pair that may be closer than this many L1000 (e.g. 8: the "
                   "every-distance mode; 0: the model's threshold), as geodex distance does")
      ->check(CLI::NonNegativeNumber);
  bench->add_option("--seed", flags->options.seed, "Random pairs seed")->capture_default_str();
  bench->add_option("--save-pairs", flags->options.save_pairs,
                    "Write the pairs drawn to this file first (lines 'fa a0 a1 a2 fb b0 b1 b2', "
                    "as geodex-query --pairs reads them; with --pairs both, the near ones), to time the same "
                    "pairs in process");
  bench->callback([flags, status] { *status = Bench(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(90, AddBenchCommand);

}  // namespace geodex::client::cli
