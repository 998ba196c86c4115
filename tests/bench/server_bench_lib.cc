#include "tests/bench/server_bench_lib.h"

#include <signal.h>
#include <sys/wait.h>

#include <atomic>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <thread>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/query/engine/query_engine.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "grpcpp/create_channel.h"
#include "server/server.h"
#include "server/model_repository_testing.h"
#include "spdlog/spdlog.h"
#include "tests/bench/bench_timing.h"
#include "tests/bench/flat_sheet_index.h"

namespace geodex::bench {
namespace {

namespace fs = std::filesystem;
using Child = server::testing::ServerProcess;
using Points = std::vector<mesh::SurfacePoint>;

constexpr char kModel[] = "bench";
constexpr int kDistinctBatches = 16;

// Prints `text` as the reason of a failed run; returns its exit code.
int Fail(const std::string& text) {
  std::fprintf(stderr, "%s\n", text.c_str());
  return 1;
}

grpc::ChannelArguments UnlimitedReceive() {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  return args;
}

// The same batches for the in-process and the served measurements.
struct Batches {
  std::vector<Points> as, bs;
  std::vector<v1::DistanceBatch> messages;
};

Batches MakeBatches(int32_t faces, int batch) {
  Batches b;
  b.messages.resize(kDistinctBatches);
  for (int k = 0; k < kDistinctBatches; ++k) {
    b.as.push_back(server::testing::RandomPoints(faces, batch, 2 * k + 1));
    b.bs.push_back(server::testing::RandomPoints(faces, batch, 2 * k + 2));
    b.messages[k].mutable_model()->set_name(kModel);
    server::testing::PointsToProto(b.as[k], b.messages[k].mutable_a());
    server::testing::PointsToProto(b.bs[k], b.messages[k].mutable_b());
  }
  return b;
}

// Publishes the throughput index at `model_index`: --index's file, or a
// torus built here. A copy that fails leaves nothing there, which the
// opening of `model_index` then reports.
void PublishIndex(const ServerBenchOptions& options, const std::string& model_index) {
  if (options.index_path.empty()) {
    std::printf("building a torus index with %d samples...\n", options.samples);
    std::fflush(stdout);
    const std::string bytes =
        server::testing::BuildIndexBytes(mesh::gen::Torus(96, 48, 2.0, 0.7), options.samples);
    std::ofstream(model_index, std::ios::binary).write(bytes.data(), bytes.size());
  } else {
    std::error_code error;
    fs::copy_file(options.index_path, model_index, error);
  }
}

// Pairs/s of DistanceBatch in this process, one thread; nullopt when a batch
// fails.
std::optional<double> InProcessRate(const query::QueryEngine& engine, const Batches& b, int batch,
                                    double seconds) {
  std::vector<double> out(batch);
  int64_t pairs = 0;
  const Clock::time_point start = Clock::now();
  for (int k = 0; SecondsSince(start) < seconds; ++k) {
    const int i = k % kDistinctBatches;
    if (!engine.DistanceBatch(b.as[i], b.bs[i], out).ok()) return std::nullopt;
    pairs += batch;
  }
  return pairs / SecondsSince(start);
}

// A server in this process over `models`, with one worker thread.
absl::StatusOr<std::unique_ptr<server::GeodexServer>> StartInProcessServer(
    const std::string& models) {
  server::ServerOptions options;
  options.models_dir = models;
  options.listen = "127.0.0.1:0";
  options.workers = 1;
  options.poll_interval = absl::ZeroDuration();
  auto srv = server::GeodexServer::Start(options);
  if (srv.ok()) (*srv)->registry().RescanNow();
  return srv;
}

// Pairs/s answered over one StreamDistances stream, after a warm-up of four
// batches. Errors: the first batch answered with an error.
absl::StatusOr<double> StreamRate(v1::Geodex::Stub& stub, Batches& b, double seconds) {
  grpc::ClientContext context;
  auto stream = stub.StreamDistances(&context);
  std::atomic<bool> stop{false};
  std::thread writer([&] {
    for (uint64_t k = 0; !stop; ++k) {
      v1::DistanceBatch& m = b.messages[k % kDistinctBatches];
      m.set_batch_id(k);
      if (!stream->Write(m)) break;
    }
    stream->WritesDone();
  });
  v1::DistanceResult result;
  for (int k = 0; k < 4 && stream->Read(&result); ++k) {
  }
  int64_t pairs = 0;
  absl::Status failed;
  const Clock::time_point start = Clock::now();
  while (SecondsSince(start) < seconds && stream->Read(&result)) {
    if (result.error_code() != 0) {
      failed = absl::InternalError("batch failed: " + result.error_message());
      break;
    }
    pairs += result.distances_size();
  }
  const double rate = pairs / SecondsSince(start);
  stop = true;
  while (stream->Read(&result)) {
  }
  writer.join();
  stream->Finish();
  if (!failed.ok()) return failed;
  return rate;
}

// Microseconds of `calls` unary Distance calls of `pairs` pairs, after 20
// calls of warm-up. Errors: a failed call, with its message.
absl::StatusOr<std::vector<double>> ServedLatenciesUs(v1::Geodex::Stub& stub,
                                                      std::span<const mesh::SurfacePoint> a,
                                                      std::span<const mesh::SurfacePoint> b,
                                                      int calls) {
  v1::DistanceRequest request;
  request.mutable_model()->set_name(kModel);
  server::testing::PointsToProto(a, request.mutable_a());
  server::testing::PointsToProto(b, request.mutable_b());
  std::vector<double> us;
  for (int i = 0; i < calls + 20; ++i) {
    grpc::ClientContext context;
    v1::DistanceResponse response;
    const Clock::time_point t0 = Clock::now();
    const grpc::Status status = stub.Distance(&context, request, &response);
    const Clock::time_point t1 = Clock::now();
    if (!status.ok()) return absl::InternalError(status.error_message());
    if (i >= 20) us.push_back(1e6 * SecondsBetween(t0, t1));
  }
  return us;
}

absl::StatusOr<LatencyFigures> MeasureLatency(v1::Geodex::Stub& stub,
                                              const query::QueryEngine& engine, const Batches& b,
                                              int pairs, int calls) {
  const auto a = std::span(b.as[0]).first(pairs), other = std::span(b.bs[0]).first(pairs);
  absl::StatusOr<std::vector<double>> served = ServedLatenciesUs(stub, a, other, calls);
  if (!served.ok()) return served.status();
  std::vector<double> local_us;
  std::vector<double> local_out(pairs);
  for (int i = 0; i < calls; ++i) {
    const Clock::time_point t0 = Clock::now();
    (void)engine.DistanceBatch(a, other, local_out);
    local_us.push_back(1e6 * SecondsSince(t0));
  }
  return LatencyFigures{.pairs = pairs,
                        .p50_us = Percentile(*served, 0.5),
                        .p99_us = Percentile(*served, 0.99),
                        .local_p50_us = Percentile(local_us, 0.5)};
}

// Throughput over one stream and unary latency, against a server in this
// process with one worker; `local_rate` is the in-process throughput.
int MeasureServing(const ServerBenchOptions& options, const std::string& models,
                   const query::QueryEngine& engine, Batches& batches, double local_rate) {
  auto srv = StartInProcessServer(models);
  if (!srv.ok()) return Fail(srv.status().ToString());
  auto stub = v1::Geodex::NewStub(
      grpc::CreateCustomChannel(absl::StrFormat("127.0.0.1:%d", (*srv)->port()),
                                grpc::InsecureChannelCredentials(), UnlimitedReceive()));
  const absl::StatusOr<double> stream_rate = StreamRate(*stub, batches, options.seconds);
  if (!stream_rate.ok()) return Fail(std::string(stream_rate.status().message()));
  std::printf("%s", ThroughputReport(options.batch, local_rate, *stream_rate).c_str());
  std::printf("\nunary Distance latency, loopback, 1 worker\n");
  for (const auto& [pairs, calls] : {std::pair{1, 3000}, std::pair{1000, 1000}}) {
    const absl::StatusOr<LatencyFigures> latency =
        MeasureLatency(*stub, engine, batches, pairs, calls);
    if (!latency.ok()) return Fail(std::string(latency.status().message()));
    std::printf("%s", LatencyLine(*latency).c_str());
  }
  (*srv)->Shutdown(absl::Seconds(5));
  return 0;
}

// --- the memory of two server processes ------------------------------------------

// Starts geodex-server over `models`, one worker, no polling.
Child StartServer(const std::string& binary, const std::string& models) {
  return server::testing::SpawnServer({binary, "--models", models, "--listen", "127.0.0.1:0",
                                       "--workers", "1", "--poll-seconds", "0", "--log-level",
                                       "warn"});
}

void StopServer(const Child& child) {
  if (child.pid <= 0) return;
  kill(child.pid, SIGTERM);
  int status = 0;
  waitpid(child.pid, &status, 0);
}

bool WaitServing(int port, const std::string& model) {
  auto stub = v1::Geodex::NewStub(grpc::CreateChannel(absl::StrFormat("127.0.0.1:%d", port),
                                                      grpc::InsecureChannelCredentials()));
  const auto until = Clock::now() + std::chrono::seconds(120);
  while (Clock::now() < until) {
    grpc::ClientContext context;
    v1::GetModelRequest request;
    request.mutable_model()->set_name(model);
    v1::ModelInfo info;
    if (stub->GetModel(&context, request, &info).ok() && info.state() == v1::ModelInfo::SERVING) {
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

// Touches the whole sample matrix of the model "sheet" through one query of
// random pairs.
void TouchSheet(int port, int32_t sheet_faces) {
  auto stub = v1::Geodex::NewStub(grpc::CreateCustomChannel(absl::StrFormat("127.0.0.1:%d", port),
                                                            grpc::InsecureChannelCredentials(),
                                                            UnlimitedReceive()));
  v1::DistanceRequest request;
  request.mutable_model()->set_name("sheet");
  server::testing::PointsToProto(server::testing::RandomPoints(sheet_faces, 20000, 5),
                                 request.mutable_a());
  server::testing::PointsToProto(server::testing::RandomPoints(sheet_faces, 20000, 6),
                                 request.mutable_b());
  grpc::ClientContext context;
  v1::DistanceResponse response;
  if (!stub->Distance(&context, request, &response).ok()) std::fprintf(stderr, "query failed\n");
}

// "Pss:" (kB) of the whole process, and of the mappings of `path`.
std::pair<int64_t, int64_t> ReadPssKb(pid_t pid, const std::string& path) {
  std::ifstream rollup(absl::StrFormat("/proc/%d/smaps_rollup", pid));
  std::ifstream smaps(absl::StrFormat("/proc/%d/smaps", pid));
  const int64_t total = RollupPssKb(rollup);
  return {total, MappedPssKb(smaps, path)};
}

// The PSS of two geodex-server processes serving one flat-sheet index.
int MeasurePss(const ServerBenchOptions& options, const std::string& dir) {
  std::printf("\nbuilding a flat-sheet index with %d samples for the memory measurement...\n",
              (options.pss_cells + 1) * (options.pss_cells + 1));
  std::fflush(stdout);
  const std::string pss_models = dir + "/pss";
  fs::create_directories(pss_models + "/sheet/1");
  const std::string sheet = pss_models + "/sheet/1/index.gdx";
  int32_t sheet_faces = 0;
  {
    const index::IndexData data = FlatSheetIndex(options.pss_cells, 3);
    sheet_faces = static_cast<int32_t>(data.faces.size() / 3);
    if (absl::Status s = index::WriteIndexFile(data, sheet); !s.ok()) return Fail(s.ToString());
  }
  const double size_kb = fs::file_size(sheet) / 1024.0;
  const Child a = StartServer(options.server_binary, pss_models);
  const Child b = StartServer(options.server_binary, pss_models);
  if (a.port == 0 || b.port == 0 || !WaitServing(a.port, "sheet") ||
      !WaitServing(b.port, "sheet")) {
    std::fprintf(stderr, "could not start two servers (%s)\n", options.server_binary.c_str());
    StopServer(a);
    StopServer(b);
    return 1;
  }
  for (const Child& c : {a, b}) TouchSheet(c.port, sheet_faces);
  std::printf("two geodex-server processes on one %.1f MiB index\n", size_kb / 1024);
  for (const Child& c : {a, b}) {
    const auto [total, mapped] = ReadPssKb(c.pid, "index.gdx");
    std::printf("%s", PssLine(c.pid, total, mapped, size_kb).c_str());
  }
  StopServer(a);
  StopServer(b);
  return 0;
}

}  // namespace

std::unique_ptr<CLI::App> ServerBenchFlags(ServerBenchOptions* options) {
  auto app = std::make_unique<CLI::App>(
      "server_bench: gRPC server throughput, latency and memory against the engine");
  app->add_option("--index", options->index_path,
                  "Index for throughput and latency (default: a built torus)");
  app->add_option("--samples", options->samples,
                  "Samples of the built torus when --index is not given");
  app->add_option("--batch", options->batch, "Pairs per stream batch");
  app->add_option("--seconds", options->seconds, "Duration of each throughput measurement");
  app->add_option("--pss-cells", options->pss_cells,
                  "Flat-sheet index for the PSS measurement: (C+1)^2 samples");
  app->add_flag("--skip-pss", options->skip_pss, "Skip the two-process memory measurement");
  app->add_option("--server-binary", options->server_binary, "geodex-server executable");
  return app;
}

int64_t RollupPssKb(std::istream& smaps_rollup) {
  int64_t total = 0;
  std::string line;
  while (std::getline(smaps_rollup, line)) {
    if (line.rfind("Pss:", 0) == 0) total = std::stoll(line.substr(4));
  }
  return total;
}

int64_t MappedPssKb(std::istream& smaps, const std::string& path_suffix) {
  int64_t mapped = 0;
  std::string line;
  bool in_file = false;
  while (std::getline(smaps, line)) {
    // A mapping's header: "start-end perms offset dev inode [path]".
    const bool header = !line.empty() && std::isxdigit(static_cast<unsigned char>(line[0])) &&
                        line.find('-') != std::string::npos && line.find(':') > line.find(' ');
    if (header) {
      in_file =
          line.size() >= path_suffix.size() &&
          line.compare(line.size() - path_suffix.size(), path_suffix.size(), path_suffix) == 0;
    } else if (in_file && line.rfind("Pss:", 0) == 0) {
      mapped += std::stoll(line.substr(4));
    }
  }
  return mapped;
}

std::string ThroughputReport(int batch, double local_rate, double stream_rate) {
  return absl::StrFormat(
      "\nthroughput, %d pairs per batch\n"
      "  in-process DistanceBatch (1 thread)        %12.0f pairs/s\n"
      "  StreamDistances, loopback, 1 worker        %12.0f pairs/s\n"
      "  ratio stream / in-process                  %12.2f\n",
      batch, local_rate, stream_rate, stream_rate / local_rate);
}

std::string LatencyLine(const LatencyFigures& f) {
  return absl::StrFormat("  %4d pairs: p50 %8.1f us  p99 %8.1f us   (in-process p50 %7.1f us)\n",
                         f.pairs, f.p50_us, f.p99_us, f.local_p50_us);
}

std::string PssLine(pid_t pid, int64_t total_kb, int64_t mapped_kb, double index_kb) {
  return absl::StrFormat(
      "  pid %d: PSS %7.1f MiB = %.2f x index  (index mapping %7.1f MiB = %.2f x; rest %.1f "
      "MiB)\n",
      pid, total_kb / 1024.0, total_kb / index_kb, mapped_kb / 1024.0, mapped_kb / index_kb,
      (total_kb - mapped_kb) / 1024.0);
}

int RunServerBench(const ServerBenchOptions& options) {
  spdlog::set_level(spdlog::level::warn);
  server::testing::TempDir dir;
  const std::string models = dir.path() + "/models";
  fs::create_directories(models + "/bench/1");
  const std::string model_index = models + "/bench/1/index.gdx";
  PublishIndex(options, model_index);
  auto index = index::Index::Open(model_index);
  if (!index.ok()) return Fail(index.status().ToString());
  auto engine = query::QueryEngine::Create(*index);
  if (!engine.ok()) return 1;
  const int32_t faces = (*index)->num_faces();
  std::printf("index: %d vertices, %d faces, %d samples, %.1f MiB\n", (*index)->num_vertices(),
              faces, (*index)->num_samples(), (*index)->size_bytes() / 1048576.0);
  Batches batches = MakeBatches(faces, options.batch);
  const std::optional<double> local_rate =
      InProcessRate(**engine, batches, options.batch, options.seconds);
  if (!local_rate.has_value()) return 1;
  if (const int code = MeasureServing(options, models, **engine, batches, *local_rate); code != 0) {
    return code;
  }
  if (options.skip_pss) return 0;
  return MeasurePss(options, dir.path());
}

}  // namespace geodex::bench
