#include "tests/soak/soak_driver_lib.h"

#include <chrono>
#include <cstdio>
#include <thread>

#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "core/index/index.h"
#include "grpcpp/create_channel.h"

namespace geodex::soak {

std::unique_ptr<CLI::App> SoakFlags(SoakOptions* options) {
  auto app = std::make_unique<CLI::App>(
      "soak_driver: concurrent valid and invalid requests, answers checked offline.");
  app->add_option("--server", options->server, "geodex-server address")->required();
  app->add_option("--model", options->model, "Model name")->required();
  app->add_option("--version", options->versions,
                  "V=INDEX: the index of version V, for the answers")
      ->required();
  app->add_option("--threads", options->threads, "Concurrent clients")->check(CLI::Range(1, 256));
  app->add_option("--seconds", options->seconds, "Run time")->check(CLI::Range(0.1, 86400.0));
  app->add_option("--max-pairs", options->max_pairs, "The server's --max-pairs")
      ->check(CLI::Range(1, 100000));
  return app;
}

absl::StatusOr<std::pair<int64_t, std::string>> ParseVersionSpec(const std::string& spec) {
  const size_t eq = spec.find('=');
  int64_t version = 0;
  if (eq == std::string::npos || !absl::SimpleAtoi(spec.substr(0, eq), &version)) {
    return absl::InvalidArgumentError("--version wants V=INDEX, got " + spec);
  }
  return std::make_pair(version, spec.substr(eq + 1));
}

absl::StatusOr<std::map<int64_t, std::shared_ptr<const query::QueryEngine>>> LoadEngines(
    const std::vector<std::string>& specs) {
  std::map<int64_t, std::shared_ptr<const query::QueryEngine>> engines;
  for (const std::string& spec : specs) {
    absl::StatusOr<std::pair<int64_t, std::string>> version = ParseVersionSpec(spec);
    if (!version.ok()) return version.status();
    auto index = index::Index::Open(version->second);
    if (!index.ok()) return absl::Status(index.status().code(), index.status().ToString());
    auto engine = query::QueryEngine::Create(*index);
    if (!engine.ok()) return absl::Status(engine.status().code(), engine.status().ToString());
    engines[version->first] = *std::move(engine);
  }
  return engines;
}

std::string SummaryLine(int threads, double seconds, const SoakTotals& totals) {
  return absl::StrFormat(
      "soak_driver: %d threads, %.0f s: %d valid calls, %d invalid refused, %d violations\n",
      threads, seconds, totals.valid, totals.invalid, totals.violations);
}

int Verdict(const SoakTotals& totals, std::string* failure) {
  if (totals.violations != 0) return 1;
  // A run that made no valid or no invalid call checked nothing (clients that
  // never got to send): it must not look like a clean soak.
  if (totals.valid == 0 || totals.invalid == 0) {
    *failure = absl::StrFormat(
        "soak_driver: FAILED: %d valid and %d invalid calls made: nothing was checked\n",
        totals.valid, totals.invalid);
    return 1;
  }
  return 0;
}

int RunSoak(const SoakOptions& options) {
  auto engines = LoadEngines(options.versions);
  if (!engines.ok()) {
    std::fprintf(stderr, "soak_driver: %s\n", std::string(engines.status().message()).c_str());
    return 2;
  }
  Soak soak(grpc::CreateChannel(options.server, grpc::InsecureChannelCredentials()), options.model,
            *std::move(engines), options.max_pairs);
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<int64_t>(options.seconds * 1000));
  std::vector<std::thread> pool;
  for (int t = 0; t < options.threads; ++t) {
    pool.emplace_back([&, t] { soak.Run(1000 + t, until); });
  }
  for (std::thread& t : pool) t.join();
  const SoakTotals totals = soak.totals();
  std::printf("%s", SummaryLine(options.threads, options.seconds, totals).c_str());
  std::string failure;
  const int code = Verdict(totals, &failure);
  if (!failure.empty()) std::fprintf(stderr, "%s", failure.c_str());
  return code;
}

}  // namespace geodex::soak
