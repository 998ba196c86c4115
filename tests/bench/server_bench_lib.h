#pragma once

// The pieces of server_bench (server_bench.cc): its flags, the reading of a
// process's proportional set size, the report lines, and the three
// measurements (throughput, latency, memory). Not thread-safe.

#include <sys/types.h>

#include <cstdint>
#include <istream>
#include <memory>
#include <string>

#include "CLI/CLI.hpp"

namespace geodex::bench {

struct ServerBenchOptions {
  std::string index_path;  // empty: a torus built with `samples` samples
  int samples = 300;
  int batch = 10000;    // pairs per stream batch
  double seconds = 3;   // duration of each throughput measurement
  int pss_cells = 100;  // flat sheet of (C+1)^2 samples for the PSS measurement
  bool skip_pss = false;
  std::string server_binary;  // geodex-server, for the PSS measurement
};

// The command line of server_bench, writing into `options` when parsed;
// options->server_binary is the default of --server-binary.
std::unique_ptr<CLI::App> ServerBenchFlags(ServerBenchOptions* options);

// The "Pss:" figure (kB) of /proc/PID/smaps_rollup's text; 0 when absent.
int64_t RollupPssKb(std::istream& smaps_rollup);

// The sum of the "Pss:" figures (kB) of the mappings in /proc/PID/smaps's
// text whose path ends in `path_suffix`.
int64_t MappedPssKb(std::istream& smaps, const std::string& path_suffix);

// The throughput section: in-process and stream pairs/s and their ratio.
std::string ThroughputReport(int batch, double local_rate, double stream_rate);

// One line of the latency section.
struct LatencyFigures {
  int pairs = 0;      // pairs per call
  double p50_us = 0;  // unary Distance over loopback
  double p99_us = 0;
  double local_p50_us = 0;  // DistanceBatch in process
};
std::string LatencyLine(const LatencyFigures& f);

// One process's line of the memory section.
std::string PssLine(pid_t pid, int64_t total_kb, int64_t mapped_kb, double index_kb);

// Runs the whole benchmark and returns the exit code: 1 when a step fails
// (the reason on stderr).
int RunServerBench(const ServerBenchOptions& options);

}  // namespace geodex::bench
