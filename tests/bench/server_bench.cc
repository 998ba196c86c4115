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
//
// The measurements and the report are in server_bench_lib.h.

#include "tests/bench/bench_flags.h"
#include "tests/bench/server_bench_lib.h"

int main(int argc, char** argv) {
  geodex::bench::ServerBenchOptions options;
  options.server_binary = GEODEX_SERVER_BINARY;
  const auto app = geodex::bench::ServerBenchFlags(&options);
  if (const auto exit_code = geodex::bench::ParseFlags(*app, argc, argv)) return *exit_code;
  return geodex::bench::RunServerBench(options);
}
