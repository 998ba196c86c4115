#include "client/cli/bench.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "client/cli/text_io.h"

namespace geodex::client::cli {
namespace {

// Weights uniform on the triangle.
std::array<double, 3> UniformWeights(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double u = unit(rng), v = unit(rng);
  if (u + v > 1) u = 1 - u, v = 1 - v;
  return {1 - u - v, u, v};
}

Position Minus(const Position& a, const Position& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
double Norm(const Position& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

double FaceArea(const Mesh& mesh, const std::array<uint32_t, 3>& f) {
  const Position u = Minus(mesh.positions[f[1]], mesh.positions[f[0]]);
  const Position v = Minus(mesh.positions[f[2]], mesh.positions[f[0]]);
  return 0.5 *
         Norm({u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]});
}

Position PointOf(const Mesh& mesh, const SurfacePoint& p) {
  Position x = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    const Position& v = mesh.positions[mesh.faces[p.face][k]];
    for (int c = 0; c < 3; ++c) x[c] += p.w[k] * v[c];
  }
  return x;
}

// Faces sharing an edge with each face (any number round an edge).
std::vector<std::vector<int32_t>> FaceNeighbours(const Mesh& mesh) {
  std::vector<std::pair<uint64_t, int32_t>> edges;
  edges.reserve(3 * mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint64_t a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
      edges.push_back({std::min(a, b) << 32 | std::max(a, b), static_cast<int32_t>(f)});
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::vector<int32_t>> neighbours(mesh.faces.size());
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    for (size_t x = i; x < j; ++x) {
      for (size_t y = i; y < j; ++y) {
        if (edges[x].second != edges[y].second) {
          neighbours[edges[x].second].push_back(edges[y].second);
        }
      }
    }
    i = j;
  }
  return neighbours;
}

}  // namespace

std::vector<PointPair> RandomPairs(int64_t num_faces, size_t count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int32_t> face(0, static_cast<int32_t>(num_faces - 1));
  auto point = [&] {
    const int32_t f = face(rng);
    return SurfacePoint{f, UniformWeights(rng)};
  };
  std::vector<PointPair> pairs(count);
  for (PointPair& p : pairs) p = {point(), point()};
  return pairs;
}

std::vector<PointPair> AreaUniformPairs(const Mesh& mesh, size_t count, uint64_t seed) {
  std::vector<double> cumulative;
  cumulative.reserve(mesh.faces.size());
  double total = 0;
  for (const auto& f : mesh.faces) cumulative.push_back(total += FaceArea(mesh, f));
  std::vector<PointPair> pairs;
  if (!(total > 0)) return pairs;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> at(0.0, total);
  auto point = [&] {
    const size_t f = std::upper_bound(cumulative.begin(), cumulative.end(), at(rng)) -
                     cumulative.begin();
    return SurfacePoint{static_cast<int32_t>(std::min(f, cumulative.size() - 1)),
                        UniformWeights(rng)};
  };
  pairs.resize(count);
  for (PointPair& p : pairs) p = {point(), point()};
  return pairs;
}

double ScaleLength(const Mesh& mesh, int64_t num_samples) {
  if (num_samples <= 0) return 0;
  double area = 0;
  for (const auto& f : mesh.faces) area += FaceArea(mesh, f);
  return area > 0 ? std::sqrt(2 * area / (std::sqrt(3.0) * num_samples)) : 0;
}

std::vector<PointPair> DrawNearPairs(const Mesh& mesh, double lo, double hi, size_t count,
                                     uint64_t seed) {
  std::vector<PointPair> pairs;
  const int32_t num_faces = static_cast<int32_t>(mesh.faces.size());
  if (num_faces == 0 || !(hi >= lo) || !(lo >= 0)) return pairs;
  const std::vector<std::vector<int32_t>> neighbours = FaceNeighbours(mesh);
  // Each face's bounding sphere, to test whether it reaches into a ball.
  std::vector<Position> centre(num_faces);
  std::vector<double> radius(num_faces);
  for (int32_t f = 0; f < num_faces; ++f) {
    centre[f] = PointOf(mesh, {f, {1.0 / 3, 1.0 / 3, 1.0 / 3}});
    radius[f] = 0;
    for (int k = 0; k < 3; ++k) {
      radius[f] = std::max(radius[f], Norm(Minus(mesh.positions[mesh.faces[f][k]], centre[f])));
    }
  }
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int32_t> any_face(0, num_faces - 1);
  std::vector<uint32_t> seen(num_faces, 0);  // the attempt that last reached a face
  std::vector<int32_t> ball;
  // A point whose ball holds no partner is skipped; give up after many in a
  // row (no pair exists at this scale).
  constexpr int kAttemptsPerPair = 64, kPartnerTries = 16;
  uint32_t attempt = 0;
  for (int misses = 0; pairs.size() < count && misses < kAttemptsPerPair;) {
    ++attempt;
    const SurfacePoint p{any_face(rng), UniformWeights(rng)};
    const Position x = PointOf(mesh, p);
    // The faces reached from p's across edges, each reaching into the ball.
    ball.assign(1, p.face);
    seen[p.face] = attempt;
    for (size_t i = 0; i < ball.size(); ++i) {
      for (const int32_t g : neighbours[ball[i]]) {
        if (seen[g] == attempt || Norm(Minus(centre[g], x)) - radius[g] > hi) continue;
        seen[g] = attempt;
        ball.push_back(g);
      }
    }
    std::uniform_int_distribution<size_t> pick(0, ball.size() - 1);
    bool found = false;
    for (int t = 0; t < kPartnerTries && !found; ++t) {
      const SurfacePoint q{ball[pick(rng)], UniformWeights(rng)};
      const double d = Norm(Minus(PointOf(mesh, q), x));
      if (d >= lo && d <= hi) {
        pairs.push_back({p, q});
        found = true;
      }
    }
    misses = found ? 0 : misses + 1;
  }
  return pairs;
}

namespace {

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
    const absl::StatusOr<Distances> d = client.Distance(
        options.model, batch,
        DistanceQuery{.near_pairs = options.near_pairs, .refine_below = options.refine_below});
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
  session_options.refine_below = options.refine_below;
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

// The pool of pairs the workers send, in turn, drawn as options.pairs says
// on the model `info` describes; sets report->scale_length for near pairs.
absl::StatusOr<std::vector<PointPair>> DrawPool(const Client& client, const BenchOptions& options,
                                                const ModelInfo& info, BenchReport* report) {
  // Area-uniform and near pairs are drawn on the mesh of the version
  // described.
  absl::StatusOr<Mesh> mesh = Mesh{};
  if (options.pairs != BenchOptions::Pairs::kUniform) {
    mesh = client.GetMesh(ModelRef(options.model.name, info.version));
    if (!mesh.ok()) return mesh.status();
  }
  std::vector<PointPair> pool;
  if (options.pairs == BenchOptions::Pairs::kArea) {
    pool = AreaUniformPairs(*mesh, std::max<size_t>(65536, 4 * static_cast<size_t>(options.batch)),
                            options.seed);
    if (pool.empty()) {
      return absl::FailedPreconditionError(
          absl::StrFormat("model %s: its mesh has no area", info.name));
    }
  } else if (options.pairs == BenchOptions::Pairs::kNear) {
    report->scale_length = ScaleLength(*mesh, info.num_samples);
    // Drawing walks the faces round each point: fewer pairs than the uniform
    // pool, used in turn.
    pool = DrawNearPairs(
        *mesh, options.near_from * report->scale_length, options.near_to * report->scale_length,
        std::max<size_t>(4096, 4 * static_cast<size_t>(options.batch)), options.seed);
    if (pool.empty()) {
      return absl::FailedPreconditionError(
          absl::StrFormat("model %s: no pairs %gL to %gL apart (L = %g)", info.name,
                          options.near_from, options.near_to, report->scale_length));
    }
    // Every batch is a slice of the pool.
    for (size_t i = 0; pool.size() < static_cast<size_t>(options.batch); ++i) {
      pool.push_back(pool[i]);
    }
  } else {
    pool =
        RandomPairs(info.num_faces, std::max<size_t>(65536, 4 * static_cast<size_t>(options.batch)),
                    options.seed);
  }
  return pool;
}

// options.concurrency workers sending from `pool` through the warm-up and
// the measured time; what each measured.
std::vector<WorkerStats> RunWorkers(const Client& client, const BenchOptions& options,
                                    const std::vector<PointPair>& pool) {
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
  return stats;
}

// The workers' figures merged into `report`; the first error when no call
// succeeded.
absl::Status Summarize(const std::vector<WorkerStats>& stats, BenchReport& report) {
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
  return absl::OkStatus();
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
  BenchReport report;
  absl::StatusOr<std::vector<PointPair>> pool = DrawPool(client, options, *info, &report);
  if (!pool.ok()) return pool.status();

  if (!options.save_pairs.empty()) {
    if (absl::Status saved = WriteFileOrStdout(options.save_pairs, FormatPairs(*pool));
        !saved.ok()) {
      return saved;
    }
  }

  const std::vector<WorkerStats> stats = RunWorkers(client, options, *pool);
  report.elapsed = options.duration;
  if (absl::Status summarized = Summarize(stats, report); !summarized.ok()) return summarized;
  return report;
}

std::string FormatBenchReport(const BenchOptions& options, const BenchReport& report) {
  const double seconds = absl::ToDoubleSeconds(report.elapsed);
  const std::string pairs =
      options.pairs == BenchOptions::Pairs::kNear
          ? absl::StrFormat("near pairs %gL-%gL apart (L = %.4g)", options.near_from,
                            options.near_to, report.scale_length)
          : options.pairs == BenchOptions::Pairs::kArea ? std::string("area-uniform pairs")
                                                        : std::string("uniform pairs");
  std::string out = absl::StrFormat(
      "model %s, %s%s, mode %s, concurrency %d, batch %d pairs%s, %.1f s measured (after %.1f s "
      "warm-up)\n",
      options.model.name, pairs,
      options.refine_below > 0
          ? absl::StrFormat(", refined below %g L1000", options.refine_below)
          : "",
      options.mode, options.concurrency, options.batch,
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
