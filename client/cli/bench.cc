#include "client/cli/bench.h"

#include <algorithm>
#include <atomic>
#include <random>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"

namespace geodex::client::cli {
namespace {

// Uniformly random points: a random face, weights uniform on the triangle.
std::vector<PointPair> RandomPairs(int64_t num_faces, size_t count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int32_t> face(0, static_cast<int32_t>(num_faces - 1));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto point = [&] {
    double u = unit(rng), v = unit(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    return SurfacePoint{face(rng), {1 - u - v, u, v}};
  };
  std::vector<PointPair> pairs(count);
  for (PointPair& p : pairs) p = {point(), point()};
  return pairs;
}

// What one worker measured.
struct WorkerStats {
  std::vector<double> latencies_ms;
  int64_t pairs = 0;
  std::map<std::string, int64_t> errors;
  absl::Status first_error;

  void Error(const absl::Status& s) {
    ++errors[absl::StatusCodeToString(s.code())];
    if (first_error.ok()) first_error = s;
  }
};

double Ms(absl::Duration d) { return absl::ToDoubleMilliseconds(d); }

void UnaryWorker(const Client& client, const BenchOptions& options,
                 const std::vector<PointPair>& pool, int worker, absl::Time measure_from,
                 absl::Time end, WorkerStats* stats) {
  size_t offset = (static_cast<size_t>(worker) * 7919 * options.batch) % pool.size();
  while (true) {
    const absl::Time start = absl::Now();
    if (start >= end) break;
    if (offset + options.batch > pool.size()) offset = 0;
    absl::Span<const PointPair> batch(pool.data() + offset, options.batch);
    offset += options.batch;
    const absl::StatusOr<std::vector<double>> d =
        client.Distance(options.model, batch, options.near_pairs);
    const absl::Time done = absl::Now();
    if (start < measure_from) continue;
    if (!d.ok()) {
      stats->Error(d.status());
      continue;
    }
    stats->latencies_ms.push_back(Ms(done - start));
    stats->pairs += options.batch;
  }
}

void StreamWorker(const Client& client, const BenchOptions& options,
                  const std::vector<PointPair>& pool, int worker, absl::Time measure_from,
                  absl::Time end, WorkerStats* stats) {
  SessionOptions session_options;
  session_options.near_pairs = options.near_pairs;
  DistanceSession session = client.OpenDistanceSession(options.model, session_options);
  absl::Mutex mu;
  std::vector<absl::Time> sent;  // send time by batch id
  int in_flight = 0;
  bool reader_done = false;

  std::thread reader([&] {
    while (std::optional<DistanceBatchResult> r = session.Read()) {
      absl::Time start;
      {
        absl::MutexLock lock(&mu);
        start = sent[r->batch_id];
        --in_flight;
      }
      const absl::Time done = absl::Now();
      if (start < measure_from || start >= end) continue;
      if (!r->status.ok()) {
        stats->Error(r->status);
        continue;
      }
      stats->latencies_ms.push_back(Ms(done - start));
      stats->pairs += static_cast<int64_t>(r->distances.size());
    }
    absl::MutexLock lock(&mu);
    reader_done = true;
  });

  size_t offset = (static_cast<size_t>(worker) * 7919 * options.batch) % pool.size();
  while (absl::Now() < end) {
    {
      absl::MutexLock lock(&mu);
      auto room = [&] { return in_flight < options.window || reader_done; };
      mu.AwaitWithDeadline(absl::Condition(&room), end);
      if (reader_done || absl::Now() >= end) break;
      ++in_flight;
      sent.push_back(absl::Now());
    }
    if (offset + options.batch > pool.size()) offset = 0;
    if (!session.Send(absl::Span<const PointPair>(pool.data() + offset, options.batch)).ok()) {
      break;
    }
    offset += options.batch;
  }
  session.CloseSend();
  reader.join();
  if (absl::Status s = session.Finish(); !s.ok()) stats->Error(s);
}

double Percentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  const size_t i = std::min(sorted.size() - 1, static_cast<size_t>(q * sorted.size()));
  return sorted[i];
}

}  // namespace

absl::StatusOr<BenchReport> RunBench(const Client& client, const BenchOptions& options) {
  if (options.concurrency < 1 || options.batch < 1 || options.window < 1) {
    return absl::InvalidArgumentError("concurrency, batch and window must be positive");
  }
  absl::StatusOr<ModelInfo> info = client.GetModel(options.model);
  if (!info.ok()) return info.status();
  if (info->num_faces <= 0) {
    return absl::FailedPreconditionError(
        absl::StrFormat("model %s has no faces (state %s)", info->name, StateName(info->state)));
  }
  const std::vector<PointPair> pool =
      RandomPairs(info->num_faces, std::max<size_t>(65536, 4 * static_cast<size_t>(options.batch)),
                  options.seed);

  std::vector<WorkerStats> stats(options.concurrency);
  const absl::Time begin = absl::Now();
  const absl::Time measure_from = begin + options.warmup;
  const absl::Time end = measure_from + options.duration;
  std::vector<std::thread> workers;
  for (int w = 0; w < options.concurrency; ++w) {
    workers.emplace_back([&, w] {
      if (options.mode == "stream") {
        StreamWorker(client, options, pool, w, measure_from, end, &stats[w]);
      } else {
        UnaryWorker(client, options, pool, w, measure_from, end, &stats[w]);
      }
    });
  }
  for (std::thread& t : workers) t.join();

  BenchReport report;
  report.elapsed = options.duration;
  std::vector<double> latencies;
  absl::Status first_error;
  for (const WorkerStats& s : stats) {
    latencies.insert(latencies.end(), s.latencies_ms.begin(), s.latencies_ms.end());
    report.pairs += s.pairs;
    for (const auto& [code, n] : s.errors) report.errors[code] += n;
    if (first_error.ok()) first_error = s.first_error;
  }
  if (latencies.empty() && !first_error.ok()) return first_error;
  std::sort(latencies.begin(), latencies.end());
  report.calls = static_cast<int64_t>(latencies.size());
  report.p50_ms = Percentile(latencies, 0.50);
  report.p90_ms = Percentile(latencies, 0.90);
  report.p99_ms = Percentile(latencies, 0.99);
  report.p999_ms = Percentile(latencies, 0.999);
  report.max_ms = latencies.empty() ? 0 : latencies.back();
  double sum = 0;
  for (double l : latencies) sum += l;
  report.mean_ms = latencies.empty() ? 0 : sum / latencies.size();
  return report;
}

std::string FormatBenchReport(const BenchOptions& options, const BenchReport& report) {
  const double seconds = absl::ToDoubleSeconds(report.elapsed);
  std::string out = absl::StrFormat(
      "model %s, mode %s, concurrency %d, batch %d pairs%s, %.1f s measured (after %.1f s "
      "warm-up)\n",
      options.model.name, options.mode, options.concurrency, options.batch,
      options.mode == "stream" ? absl::StrFormat(", window %d", options.window) : "", seconds,
      absl::ToDoubleSeconds(options.warmup));
  absl::StrAppendFormat(&out, "calls       %d ok", report.calls);
  for (const auto& [code, n] : report.errors) absl::StrAppendFormat(&out, ", %d %s", n, code);
  absl::StrAppendFormat(&out, "\nthroughput  %.1f calls/s, %.0f pairs/s\n", report.calls / seconds,
                        report.pairs / seconds);
  absl::StrAppendFormat(&out,
                        "latency ms  p50 %.3f  p90 %.3f  p99 %.3f  p99.9 %.3f  max %.3f  "
                        "mean %.3f\n",
                        report.p50_ms, report.p90_ms, report.p99_ms, report.p999_ms, report.max_ms,
                        report.mean_ms);
  return out;
}

}  // namespace geodex::client::cli
