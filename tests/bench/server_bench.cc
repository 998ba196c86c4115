// server_bench: what the gRPC server costs over the in-process engine.
//
//   server_bench [--index FILE.gdx] [--samples M] [--batch P] [--seconds S]
//                [--pss-cells C] [--skip-pss]
//
// 1. Throughput: pairs/s of QueryEngine::DistanceBatch in this process
//    (one thread) against pairs/s over one StreamDistances stream on a
//    loopback TCP port to a server with ONE worker thread, measured in the
//    same run on the same batches; the ratio is the figure of merit.
// 2. Latency: p50/p99 of a 1-pair Distance call and of a 1000-pair call.
// 3. Memory: PSS of two geodex-server processes serving one index file
//    (/proc/PID/smaps_rollup, and the index mapping's own Pss from
//    /proc/PID/smaps), against the index size. The index is a synthetic
//    flat sheet (exact Euclidean distances, every section filled and valid)
//    large enough that the processes' fixed overhead does not dominate;
//    building a real index of that size takes hours here.
//
// The throughput index is FILE.gdx, or a torus built with M samples.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/index/face_bvh.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/query/internal/query_engine.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "grpcpp/create_channel.h"
#include "server/server.h"
#include "server/test_util.h"
#include "spdlog/spdlog.h"

namespace geodex {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

double Percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5))];
}

// --- the synthetic flat-sheet index for the memory measurement ---------------------

// A unit-spaced planar grid of `cells` x `cells` geodesic triangles pairs
// (samples at the coarse grid points), each coarse cell split into `fine` x
// `fine` mesh cells. Distances on a flat sheet are Euclidean, so every
// section is exact.
index::IndexData FlatSheetIndex(int cells, int fine) {
  index::IndexData d;
  const int n = cells * fine + 1;  // fine vertices per side
  auto vid = [n](int i, int j) { return j * n + i; };
  d.positions.reserve(3 * n * n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      d.positions.insert(d.positions.end(), {double(i) / fine, double(j) / fine, 0.0});
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {  // diagonal from (i,j) to (i+1,j+1), CCW faces
      d.faces.insert(d.faces.end(), {vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)});
      d.faces.insert(d.faces.end(), {vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)});
    }
  }
  // Half-edge twins.
  std::unordered_map<uint64_t, int32_t> half_edges;
  auto key = [](int32_t a, int32_t b) { return (uint64_t(uint32_t(a)) << 32) | uint32_t(b); };
  const int32_t num_faces = static_cast<int32_t>(d.faces.size() / 3);
  for (int32_t f = 0; f < num_faces; ++f) {
    for (int e = 0; e < 3; ++e)
      half_edges[key(d.faces[3 * f + e], d.faces[3 * f + (e + 1) % 3])] = 3 * f + e;
  }
  d.twins.resize(d.faces.size());
  for (int32_t h = 0; h < 3 * num_faces; ++h) {
    const int32_t f = h / 3, e = h % 3;
    auto it = half_edges.find(key(d.faces[3 * f + (e + 1) % 3], d.faces[3 * f + e]));
    d.twins[h] = it == half_edges.end() ? -1 : it->second;
  }
  // Samples: the coarse grid points; geodesic triangles like the faces.
  const int m = cells + 1;
  auto sid = [m](int i, int j) { return j * m + i; };
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < m; ++i) d.samples.push_back(vid(i * fine, j * fine));
  }
  const int32_t num_samples = m * m;
  d.sample_distances.resize(size_t(num_samples) * num_samples);
  for (int32_t a = 0; a < num_samples; ++a) {
    const double ax = a % m, ay = a / m;
    for (int32_t b = 0; b < num_samples; ++b) {
      d.sample_distances[size_t(a) * num_samples + b] =
          static_cast<float>(std::hypot(ax - b % m, ay - b / m));
    }
  }
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      d.triangles.push_back({{sid(i, j), sid(i + 1, j), sid(i + 1, j + 1)}, {-1, -1, -1}});
      d.triangles.push_back({{sid(i, j), sid(i + 1, j + 1), sid(i, j + 1)}, {-1, -1, -1}});
    }
  }
  std::map<std::pair<int32_t, int32_t>, int32_t> sides;
  for (int32_t t = 0; t < static_cast<int32_t>(d.triangles.size()); ++t) {
    for (int e = 0; e < 3; ++e)
      sides[{d.triangles[t].corner[e], d.triangles[t].corner[(e + 1) % 3]}] = t;
  }
  for (auto& t : d.triangles) {
    for (int e = 0; e < 3; ++e) {
      auto it = sides.find({t.corner[(e + 1) % 3], t.corner[e]});
      t.neighbor[e] = it == sides.end() ? -1 : it->second;
    }
  }
  // Each vertex in the geodesic triangle of its coarse cell.
  d.vertices.resize(size_t(n) * n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int ci = std::min(i / fine, cells - 1), cj = std::min(j / fine, cells - 1);
      const double x = double(i) / fine - ci, y = double(j) / fine - cj;  // within the cell
      const int32_t t = 2 * (cj * cells + ci) + (y > x ? 1 : 0);
      index::VertexRecord& r = d.vertices[vid(i, j)];
      r.triangle = t;
      r.flags = 0;
      for (int c = 0; c < 3; ++c) {
        const int32_t s = d.triangles[t].corner[c];
        r.corner[c] = s;
        r.distance[c] =
            static_cast<float>(std::hypot(double(i) / fine - s % m, double(j) / fine - s / m));
      }
    }
  }
  index::BuildFaceBvh(d.positions, d.faces, &d.bvh_nodes, &d.bvh_faces);
  d.builder_version = "server_bench flat sheet";
  d.mesh_hash = index::MeshHash(d.positions, d.faces);
  d.params.requested_samples = num_samples;
  d.params.num_samples = num_samples;
  d.report = absl::StrFormat("synthetic = flat sheet %dx%d cells, %d fine\n", cells, cells, fine);
  return d;
}

// --- child server processes ------------------------------------------------------

using Child = server::testing::ServerProcess;

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

// "Pss:" (kB) of the whole process, and of the mappings of `path`.
std::pair<int64_t, int64_t> ReadPssKb(pid_t pid, const std::string& path) {
  int64_t total = 0, mapped = 0;
  {
    std::ifstream in(absl::StrFormat("/proc/%d/smaps_rollup", pid));
    std::string line;
    while (std::getline(in, line)) {
      if (line.rfind("Pss:", 0) == 0) total = std::stoll(line.substr(4));
    }
  }
  std::ifstream in(absl::StrFormat("/proc/%d/smaps", pid));
  std::string line;
  bool in_file = false;
  while (std::getline(in, line)) {
    const bool header = !line.empty() && std::isxdigit(static_cast<unsigned char>(line[0])) &&
                        line.find('-') != std::string::npos && line.find(':') > line.find(' ');
    if (header) {
      in_file = line.size() >= path.size() &&
                line.compare(line.size() - path.size(), path.size(), path) == 0;
    } else if (in_file && line.rfind("Pss:", 0) == 0) {
      mapped += std::stoll(line.substr(4));
    }
  }
  return {total, mapped};
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

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  using namespace geodex;
  std::string index_path;
  int samples = 300;
  int batch = 10000;
  double seconds = 3;
  int pss_cells = 100;
  bool skip_pss = false;
  std::string server_binary = GEODEX_SERVER_BINARY;
  CLI::App app{"server_bench: gRPC server throughput, latency and memory against the engine"};
  app.add_option("--index", index_path,
                 "Index for throughput and latency (default: a built torus)");
  app.add_option("--samples", samples, "Samples of the built torus when --index is not given");
  app.add_option("--batch", batch, "Pairs per stream batch");
  app.add_option("--seconds", seconds, "Duration of each throughput measurement");
  app.add_option("--pss-cells", pss_cells,
                 "Flat-sheet index for the PSS measurement: (C+1)^2 samples");
  app.add_flag("--skip-pss", skip_pss, "Skip the two-process memory measurement");
  app.add_option("--server-binary", server_binary, "geodex-server executable");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::warn);

  server::testing::TempDir dir;
  const std::string models = dir.path() + "/models";
  fs::create_directories(models + "/bench/1");
  const std::string model_index = models + "/bench/1/index.gdx";
  if (index_path.empty()) {
    std::printf("building a torus index with %d samples...\n", samples);
    std::fflush(stdout);
    const std::string bytes =
        server::testing::BuildIndexBytes(mesh::gen::Torus(96, 48, 2.0, 0.7), samples);
    std::ofstream(model_index, std::ios::binary).write(bytes.data(), bytes.size());
  } else {
    fs::copy_file(index_path, model_index);
  }
  auto index = index::Index::Open(model_index);
  if (!index.ok()) {
    std::fprintf(stderr, "%s\n", index.status().ToString().c_str());
    return 1;
  }
  auto engine = query::QueryEngine::Create(*index);
  if (!engine.ok()) return 1;
  const int32_t faces = (*index)->num_faces();
  std::printf("index: %d vertices, %d faces, %d samples, %.1f MiB\n", (*index)->num_vertices(),
              faces, (*index)->num_samples(), (*index)->size_bytes() / 1048576.0);

  // The same batches for both measurements.
  constexpr int kDistinctBatches = 16;
  std::vector<std::vector<mesh::SurfacePoint>> as, bs;
  std::vector<v1::DistanceBatch> messages(kDistinctBatches);
  for (int k = 0; k < kDistinctBatches; ++k) {
    as.push_back(server::testing::RandomPoints(faces, batch, 2 * k + 1));
    bs.push_back(server::testing::RandomPoints(faces, batch, 2 * k + 2));
    messages[k].mutable_model()->set_name("bench");
    server::testing::PointsToProto(as[k], messages[k].mutable_a());
    server::testing::PointsToProto(bs[k], messages[k].mutable_b());
  }

  // 1a. In-process.
  std::vector<double> out(batch);
  int64_t local_pairs = 0;
  auto start = Clock::now();
  for (int k = 0; Seconds(start, Clock::now()) < seconds; ++k) {
    if (!(*engine)->DistanceBatch(as[k % kDistinctBatches], bs[k % kDistinctBatches], out).ok())
      return 1;
    local_pairs += batch;
  }
  const double local_rate = local_pairs / Seconds(start, Clock::now());

  // 1b. One stream to a server with one worker thread.
  server::ServerOptions options;
  options.models_dir = models;
  options.listen = "127.0.0.1:0";
  options.workers = 1;
  options.poll_interval = absl::ZeroDuration();
  auto srv = server::GeodexServer::Start(options);
  if (!srv.ok()) {
    std::fprintf(stderr, "%s\n", srv.status().ToString().c_str());
    return 1;
  }
  (*srv)->registry().RescanNow();
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  auto channel = grpc::CreateCustomChannel(absl::StrFormat("127.0.0.1:%d", (*srv)->port()),
                                           grpc::InsecureChannelCredentials(), args);
  auto stub = v1::Geodex::NewStub(channel);
  double stream_rate = 0;
  {
    grpc::ClientContext context;
    auto stream = stub->StreamDistances(&context);
    std::atomic<bool> stop{false};
    std::atomic<int64_t> sent{0};
    std::thread writer([&] {
      for (uint64_t k = 0; !stop; ++k) {
        v1::DistanceBatch& m = messages[k % kDistinctBatches];
        m.set_batch_id(k);
        if (!stream->Write(m)) break;
        ++sent;
      }
      stream->WritesDone();
    });
    v1::DistanceResult result;
    // Warm up, then measure.
    for (int k = 0; k < 4 && stream->Read(&result); ++k) {
    }
    int64_t pairs = 0;
    start = Clock::now();
    while (Seconds(start, Clock::now()) < seconds && stream->Read(&result)) {
      if (result.error_code() != 0) {
        std::fprintf(stderr, "batch failed: %s\n", result.error_message().c_str());
        return 1;
      }
      pairs += result.distances_size();
    }
    stream_rate = pairs / Seconds(start, Clock::now());
    stop = true;
    while (stream->Read(&result)) {
    }
    writer.join();
    stream->Finish();
  }
  std::printf("\nthroughput, %d pairs per batch\n", batch);
  std::printf("  in-process DistanceBatch (1 thread)        %12.0f pairs/s\n", local_rate);
  std::printf("  StreamDistances, loopback, 1 worker        %12.0f pairs/s\n", stream_rate);
  std::printf("  ratio stream / in-process                  %12.2f\n", stream_rate / local_rate);

  // 2. Latency.
  auto latency = [&](int pairs, int calls) {
    v1::DistanceRequest request;
    request.mutable_model()->set_name("bench");
    server::testing::PointsToProto(std::span(as[0]).first(pairs), request.mutable_a());
    server::testing::PointsToProto(std::span(bs[0]).first(pairs), request.mutable_b());
    std::vector<double> us;
    for (int i = 0; i < calls + 20; ++i) {
      grpc::ClientContext context;
      v1::DistanceResponse response;
      const auto t0 = Clock::now();
      const grpc::Status status = stub->Distance(&context, request, &response);
      const auto t1 = Clock::now();
      if (!status.ok()) {
        std::fprintf(stderr, "%s\n", status.error_message().c_str());
        std::exit(1);
      }
      if (i >= 20) us.push_back(1e6 * Seconds(t0, t1));  // after a warm-up
    }
    std::vector<double> local_us;
    std::vector<double> local_out(pairs);
    for (int i = 0; i < calls; ++i) {
      const auto t0 = Clock::now();
      (void)(*engine)->DistanceBatch(std::span(as[0]).first(pairs), std::span(bs[0]).first(pairs),
                                     local_out);
      local_us.push_back(1e6 * Seconds(t0, Clock::now()));
    }
    std::printf("  %4d pairs: p50 %8.1f us  p99 %8.1f us   (in-process p50 %7.1f us)\n", pairs,
                Percentile(us, 0.5), Percentile(us, 0.99), Percentile(local_us, 0.5));
  };
  std::printf("\nunary Distance latency, loopback, 1 worker\n");
  latency(1, 3000);
  latency(1000, 1000);
  (*srv)->Shutdown(absl::Seconds(5));

  // 3. Memory of two server processes on one index.
  if (!skip_pss) {
    std::printf("\nbuilding a flat-sheet index with %d samples for the memory measurement...\n",
                (pss_cells + 1) * (pss_cells + 1));
    std::fflush(stdout);
    const std::string pss_models = dir.path() + "/pss";
    fs::create_directories(pss_models + "/sheet/1");
    const std::string sheet = pss_models + "/sheet/1/index.gdx";
    if (absl::Status s = index::WriteIndexFile(FlatSheetIndex(pss_cells, 3), sheet); !s.ok()) {
      std::fprintf(stderr, "%s\n", s.ToString().c_str());
      return 1;
    }
    const double size_kb = fs::file_size(sheet) / 1024.0;
    Child a = StartServer(server_binary, pss_models);
    Child b = StartServer(server_binary, pss_models);
    if (a.port == 0 || b.port == 0 || !WaitServing(a.port, "sheet") ||
        !WaitServing(b.port, "sheet")) {
      std::fprintf(stderr, "could not start two servers (%s)\n", server_binary.c_str());
      StopServer(a);
      StopServer(b);
      return 1;
    }
    // Touch the whole matrix through queries on both servers.
    for (const Child& c : {a, b}) {
      auto s = v1::Geodex::NewStub(grpc::CreateCustomChannel(
          absl::StrFormat("127.0.0.1:%d", c.port), grpc::InsecureChannelCredentials(), args));
      v1::DistanceRequest request;
      request.mutable_model()->set_name("sheet");
      auto info_index = index::Index::Open(sheet);
      const int32_t sheet_faces = (*info_index)->num_faces();
      server::testing::PointsToProto(server::testing::RandomPoints(sheet_faces, 20000, 5),
                                     request.mutable_a());
      server::testing::PointsToProto(server::testing::RandomPoints(sheet_faces, 20000, 6),
                                     request.mutable_b());
      grpc::ClientContext context;
      v1::DistanceResponse response;
      if (!s->Distance(&context, request, &response).ok()) std::fprintf(stderr, "query failed\n");
    }
    std::printf("two geodex-server processes on one %.1f MiB index\n", size_kb / 1024);
    for (const Child& c : {a, b}) {
      const auto [total, mapped] = ReadPssKb(c.pid, "index.gdx");
      std::printf(
          "  pid %d: PSS %7.1f MiB = %.2f x index  (index mapping %7.1f MiB = %.2f x; rest %.1f "
          "MiB)\n",
          c.pid, total / 1024.0, total / size_kb, mapped / 1024.0, mapped / size_kb,
          (total - mapped) / 1024.0);
    }
    StopServer(a);
    StopServer(b);
  }
  return 0;
}
