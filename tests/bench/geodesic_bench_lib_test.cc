#include "tests/bench/geodesic_bench_lib.h"

#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_split.h"
#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/bench/bench_flags.h"
#include "tests/bench/geodesic_bench_engines.h"

namespace geodex::bench {
namespace {

using ::testing::HasSubstr;

constexpr double kInf = std::numeric_limits<double>::infinity();

ChildResult SomeResult() {
  ChildResult r;
  r.error = "";
  r.setup_seconds = 0.25;
  r.seconds = {1, 2};
  r.cpu_seconds = {0.5, 1.5};
  r.baseline_kb = 100;
  r.peak_kb = 300;
  r.windows = 12345;
  r.distances = {{0, 1, kInf}, {}, {2.5}};
  return r;
}

TEST(ChildResultTest, RoundTripsThroughBytes) {
  const ChildResult r = SomeResult();
  absl::StatusOr<ChildResult> back = DeserializeChildResult(SerializeChildResult(r));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->error, r.error);
  EXPECT_EQ(back->setup_seconds, r.setup_seconds);
  EXPECT_EQ(back->seconds, r.seconds);
  EXPECT_EQ(back->cpu_seconds, r.cpu_seconds);
  EXPECT_EQ(back->baseline_kb, r.baseline_kb);
  EXPECT_EQ(back->peak_kb, r.peak_kb);
  EXPECT_EQ(back->windows, r.windows);
  EXPECT_EQ(back->distances, r.distances);
}

TEST(ChildResultTest, TruncatedBytesAreAnError) {
  std::string bytes = SerializeChildResult(SomeResult());
  bytes.resize(bytes.size() - 3);
  EXPECT_EQ(DeserializeChildResult(bytes).status().code(), absl::StatusCode::kInternal);
  EXPECT_FALSE(DeserializeChildResult("").ok());
}

TEST(InChildTest, ReturnsWhatTheChildReports) {
  const pid_t parent = getpid();
  absl::StatusOr<ChildResult> r = InChild([&] {
    ChildResult c;
    c.error = getpid() == parent ? "ran in the parent" : "";
    c.windows = 7;
    return c;
  });
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->error, "");
  EXPECT_EQ(r->windows, 7);
}

TEST(InChildTest, SaysHowTheChildEnded) {
  absl::StatusOr<ChildResult> exited = InChild([]() -> ChildResult { _exit(3); });
  EXPECT_THAT(exited.status().message(), HasSubstr("child exited with status 3"));
  absl::StatusOr<ChildResult> killed = InChild([]() -> ChildResult {
    raise(SIGKILL);
    return {};
  });
  EXPECT_THAT(killed.status().message(), HasSubstr("child killed by signal 9"));
}

TEST(EnginesTest, OursAgreeAndCgalAgreesWithThem) {
  const mesh::Mesh m = mesh::gen::Sphere(2, 1.0);
  const std::vector<int32_t> sources = PickSources(m, 2);
  const ChildResult front = RunOurs(m, sources, /*wavefront=*/true, /*keep=*/1);
  const ChildResult windows = RunOurs(m, sources, /*wavefront=*/false, /*keep=*/2);
  ASSERT_EQ(front.error, "");
  ASSERT_EQ(windows.error, "");
  EXPECT_EQ(front.seconds.size(), 2u);
  EXPECT_EQ(front.cpu_seconds.size(), 2u);
  ASSERT_EQ(front.distances.size(), 1u);
  ASSERT_EQ(windows.distances.size(), 2u);
  ASSERT_EQ(front.distances[0].size(), static_cast<size_t>(m.num_vertices()));
  EXPECT_EQ(front.distances[0][sources[0]], 0);
  EXPECT_LT(MaxRelativeDifference(front.distances[0], windows.distances[0]), 1e-9);
  const ChildResult cgal = RunCgal(m, {*mesh::VertexPoint(m, sources[0])});
  ASSERT_EQ(cgal.error, "");
  ASSERT_EQ(cgal.distances.size(), 1u);
  EXPECT_LT(MaxRelativeDifference(front.distances[0], cgal.distances[0]), 1e-9);
}

TEST(EnginesTest, MaxRelativeDifference) {
  EXPECT_EQ(MaxRelativeDifference({1, 2, kInf}, {1, 2, kInf}), 0);
  EXPECT_DOUBLE_EQ(MaxRelativeDifference({1, 2, 4}, {1, 2.2, 5}), 0.2);
  EXPECT_EQ(MaxRelativeDifference({1, kInf}, {1, 3}), kInf);
  EXPECT_EQ(MaxRelativeDifference({1, 2}, {1}), 0);  // only the common vertices
}

TEST(EnginesTest, VtpPropagationSeconds) {
  std::istringstream printed("reading mesh\nPropagation took 0.0165 seconds\n");
  EXPECT_DOUBLE_EQ(VtpPropagationSeconds(printed), 0.0165);
  std::istringstream silent("nothing here\n");
  EXPECT_EQ(VtpPropagationSeconds(silent), -1);
}

TEST(HarnessTest, PickSourcesIsFixedAndReferenced) {
  const mesh::Mesh m = mesh::gen::Sphere(2, 1.0);
  const std::vector<int32_t> a = PickSources(m, 5), b = PickSources(m, 5);
  EXPECT_EQ(a, b);
  ASSERT_EQ(a.size(), 5u);
  for (int32_t v : a) {
    EXPECT_GE(v, 0);
    EXPECT_LT(v, m.num_vertices());
    EXPECT_TRUE(m.IsReferenced(v));
  }
  EXPECT_EQ(PickSources(m, 2), std::vector<int32_t>(a.begin(), a.begin() + 2));
}

TEST(HarnessTest, CgalSourceCount) {
  GeodesicBenchOptions options;
  options.sources = 3;
  options.cgal_large_sources = 1;
  options.large_vertices = 1000;
  EXPECT_EQ(CgalSourceCount(options, 999), 3);
  EXPECT_EQ(CgalSourceCount(options, 1000), 1);
  options.cgal_large_sources = 5;
  EXPECT_EQ(CgalSourceCount(options, 5000), 3);
  options.no_cgal = true;
  EXPECT_EQ(CgalSourceCount(options, 10), 0);
  EXPECT_EQ(Megabytes(1536), "1.5 MB");
}

TEST(HarnessTest, ComparisonRowsAgainstVtp) {
  std::vector<Measured> measured = {
      {"ours, wavefront (rows)", 2, 0.0831, 0.011, "0.8 MB", {{1, 2}, {3, 4}}},
      {"CGAL", 1, 1.2644, 0.24, "36.2 MB", {{1, 2.0000000001}}},
      {"VTP", 2, 0.255, 0.016, "8.1 MB (process)", {{1, 2.2}, {3, 4}}},
  };
  EXPECT_EQ(ComparisonRows("m.obj", 3485, measured),
            (std::vector<std::string>{
                "| m.obj | 3485 | ours, wavefront (rows) | 2 | 0.083 | 0.011 | 0.8 MB | 0.69 | "
                "9.1e-02 |",
                "| m.obj | 3485 | CGAL | 1 | 1.264 | 0.240 | 36.2 MB | 15.00 | 9.1e-02 |",
                "| m.obj | 3485 | VTP | 2 | 0.255 | 0.016 | 8.1 MB (process) | - | 9.1e-02 |",
            }));
  measured.pop_back();  // without VTP: no comparison columns
  EXPECT_EQ(ComparisonRows("m.obj", 3485, measured)[1],
            "| m.obj | 3485 | CGAL | 1 | 1.264 | 0.240 | 36.2 MB | - | - |");
}

TEST(HarnessTest, ResultsReportLayout) {
  const std::string report = ResultsReport({"| a | row |"}, {"first note", "second note"});
  const std::vector<std::string> lines = absl::StrSplit(report, '\n');
  ASSERT_EQ(lines.size(), 8u);
  EXPECT_THAT(lines[0], HasSubstr("| mesh | vertices | engine |"));
  EXPECT_EQ(lines[1], "|---|---:|---|---:|---:|---:|---:|---:|---:|");
  EXPECT_EQ(lines[2], "| a | row |");
  EXPECT_EQ(lines[3], "");
  EXPECT_EQ(lines[4], "- first note");
  EXPECT_EQ(lines[5], "- second note");
  EXPECT_THAT(lines[6], HasSubstr("- vertex sources (fixed seed)"));
  EXPECT_EQ(lines[7], "");
}

TEST(GeodesicBenchFlagsTest, DefaultsValuesAndChecks) {
  GeodesicBenchOptions options;
  auto app = GeodesicBenchFlags(&options);
  std::ostringstream out, err;
  ASSERT_EQ(ParseFlags(*app, {"geodesic_bench", "--no-cgal", "--sources", "2"}, out, err),
            std::nullopt);
  EXPECT_TRUE(options.no_cgal);
  EXPECT_FALSE(options.no_windows);
  EXPECT_EQ(options.sources, 2);
  EXPECT_EQ(options.cgal_large_sources, 1);
  EXPECT_EQ(options.large_vertices, 50000);
  GeodesicBenchOptions other;
  auto app2 = GeodesicBenchFlags(&other);
  EXPECT_NE(ParseFlags(*app2, {"geodesic_bench", "--sources", "0"}, out, err).value_or(0), 0);
  auto app3 = GeodesicBenchFlags(&other);
  EXPECT_NE(
      ParseFlags(*app3, {"geodesic_bench", "--mesh", "/nonexistent.obj"}, out, err).value_or(0), 0);
  auto app4 = GeodesicBenchFlags(&other);
  std::ostringstream help;
  EXPECT_EQ(ParseFlags(*app4, {"geodesic_bench", "--help"}, help, err), 0);
  EXPECT_THAT(help.str(), HasSubstr("--sources INT:POSITIVE=3"));
}

}  // namespace
}  // namespace geodex::bench
