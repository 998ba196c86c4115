#include "tests/bench/server_bench_lib.h"

#include <cmath>
#include <sstream>
#include <string>

#include "absl/strings/str_format.h"
#include "core/index/index.h"
#include "core/query/engine/query_engine.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/bench/bench_flags.h"
#include "tests/bench/flat_sheet_index.h"

namespace geodex::bench {
namespace {

using ::testing::HasSubstr;

// Every option, on one line.
std::string Describe(const ServerBenchOptions& o) {
  return absl::StrFormat(
      "index=%s samples=%d batch=%d seconds=%g pss_cells=%d skip_pss=%d binary=%s", o.index_path,
      o.samples, o.batch, o.seconds, o.pss_cells, o.skip_pss, o.server_binary);
}

TEST(ServerBenchFlagsTest, DefaultsAndValues) {
  ServerBenchOptions options;
  options.server_binary = "/usr/bin/geodex-server";
  auto app = ServerBenchFlags(&options);
  std::ostringstream out, err;
  ASSERT_EQ(ParseFlags(*app, {"server_bench"}, out, err), std::nullopt);
  EXPECT_EQ(Describe(options),
            "index= samples=300 batch=10000 seconds=3 pss_cells=100 skip_pss=0 "
            "binary=/usr/bin/geodex-server");
  auto app2 = ServerBenchFlags(&options);
  ASSERT_EQ(ParseFlags(
                *app2,
                {"server_bench", "--index", "x.gdx", "--samples", "50", "--batch", "7", "--seconds",
                 "0.5", "--pss-cells", "4", "--skip-pss", "--server-binary", "/opt/s"},
                out, err),
            std::nullopt);
  EXPECT_EQ(Describe(options),
            "index=x.gdx samples=50 batch=7 seconds=0.5 pss_cells=4 skip_pss=1 binary=/opt/s");
  const std::string help = ServerBenchFlags(&options)->help();
  EXPECT_THAT(help, HasSubstr("gRPC server throughput, latency and memory"));
  EXPECT_THAT(help, HasSubstr("--skip-pss"));
}

TEST(ServerBenchPssTest, ReadsTheRollupAndTheMappingsOfOneFile) {
  std::istringstream rollup(
      "55d0c0a00000-7ffd5b5fe000 ---p 00000000 00:00 0    [rollup]\n"
      "Rss:               12000 kB\n"
      "Pss:                9000 kB\n"
      "Pss_Anon:           3000 kB\n");
  EXPECT_EQ(RollupPssKb(rollup), 9000);
  std::istringstream smaps(
      "7f0000000000-7f0000100000 r--s 00000000 08:01 1234   /tmp/m/sheet/1/index.gdx\n"
      "Size:               1024 kB\n"
      "Pss:                 512 kB\n"
      "Pss_Dirty:             0 kB\n"
      "7f0000200000-7f0000300000 r-xp 00000000 08:01 99     /usr/lib/libc.so.6\n"
      "Pss:                 100 kB\n"
      "7f0000400000-7f0000500000 r--s 00000000 08:01 1234   /tmp/m/sheet/1/index.gdx\n"
      "Pss:                  40 kB\n"
      "7ffd00000000-7ffd00001000 rw-p 00000000 00:00 0\n"
      "Pss:                   4 kB\n");
  EXPECT_EQ(MappedPssKb(smaps, "index.gdx"), 552);
  std::istringstream none("");
  EXPECT_EQ(RollupPssKb(none), 0);
}

TEST(ServerBenchReportTest, Lines) {
  EXPECT_EQ(ThroughputReport(10000, 2e6, 1e6),
            "\nthroughput, 10000 pairs per batch\n"
            "  in-process DistanceBatch (1 thread)             2000000 pairs/s\n"
            "  StreamDistances, loopback, 1 worker             1000000 pairs/s\n"
            "  ratio stream / in-process                          0.50\n");
  EXPECT_EQ(LatencyLine({.pairs = 1, .p50_us = 80.24, .p99_us = 300, .local_p50_us = 0.4}),
            "     1 pairs: p50     80.2 us  p99    300.0 us   (in-process p50     0.4 us)\n");
  EXPECT_EQ(PssLine(42, 3072, 2048, 4096),
            "  pid 42: PSS     3.0 MiB = 0.75 x index  (index mapping     2.0 MiB = 0.50 x; rest "
            "1.0 MiB)\n");
}

// The flat sheet is a valid index whose distances are the plane's.
TEST(FlatSheetIndexTest, IsAValidIndexOfThePlane) {
  const index::IndexData data = FlatSheetIndex(2, 2);
  EXPECT_EQ(data.positions.size(), 3u * 25);
  EXPECT_EQ(data.faces.size(), 3u * 32);
  EXPECT_EQ(data.samples.size(), 9u);
  EXPECT_EQ(data.triangles.size(), 8u);
  auto bytes = index::SerializeIndex(data);
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  auto ix = index::Index::FromBytes(*std::move(bytes));
  ASSERT_TRUE(ix.ok()) << ix.status();
  EXPECT_EQ((*ix)->num_samples(), 9);
  EXPECT_FLOAT_EQ((*ix)->SampleDistance(0, 8), std::sqrt(8.0f));
  auto engine = query::QueryEngine::Create(*ix);
  ASSERT_TRUE(engine.ok()) << engine.status();
  // Faces 2k and 2k + 1 split fine cell k (row-major, 4 per row); vertex
  // (0, 0) is corner 0 of face 0, vertex (4, 4), at (2, 2), corner 2 of face
  // 30.
  const mesh::SurfacePoint origin{0, {1, 0, 0}}, corner{30, {0, 0, 1}};
  EXPECT_NEAR((*engine)->O1Distance(origin, corner), std::sqrt(8.0), 1e-6);
  const mesh::SurfacePoint middle{10, {0, 0, 1}};  // vertex (2, 2), at (1, 1)
  EXPECT_NEAR((*engine)->O1Distance(origin, middle), std::sqrt(2.0), 1e-6);
}

}  // namespace
}  // namespace geodex::bench
