#include "tests/bench/query_bench_lib.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_split.h"
#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/mesh/generators.h"
#include "core/build/build_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/bench/bench_flags.h"

namespace geodex::bench {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

// Columns of a Markdown row: its bars less one.
int Columns(const std::string& row) {
  return static_cast<int>(std::count(row.begin(), row.end(), '|')) - 1;
}

std::vector<std::string> Lines(const std::string& text) {
  return absl::StrSplit(text, '\n', absl::SkipEmpty());
}

std::shared_ptr<const index::Index> SmallIndex(bool calibrate) {
  auto bytes = testing::BuildTestIndex(mesh::gen::Sphere(3, 1.0), 40, calibrate);
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  auto ix = index::Index::FromBytes(*std::move(bytes));
  EXPECT_TRUE(ix.ok()) << ix.status();
  return *ix;
}

TEST(QueryBenchFlagsTest, DefaultsAndValues) {
  QueryBenchOptions options;
  auto app = QueryBenchFlags(&options);
  std::ostringstream out, err;
  ASSERT_EQ(ParseFlags(*app, {"query_bench"}, out, err), std::nullopt);
  EXPECT_TRUE(options.indexes.empty());
  EXPECT_EQ(options.pairs, 1'000'000);
  EXPECT_FALSE(options.field_only);
  ASSERT_FALSE(QueryBenchTables().empty());  // the registered tables are linked in
  for (const QueryBenchTable* table : QueryBenchTables()) {
    EXPECT_FALSE(options.table_only.at(table->flag)) << table->flag;

    QueryBenchOptions set;
    auto app2 = QueryBenchFlags(&set);
    const std::string only = "--" + table->flag + "-only";
    ASSERT_EQ(ParseFlags(*app2,
                         {"query_bench", "--index", "a.gdx", "--index", "b.gdx", "--pairs", "20",
                          only.c_str()},
                         out, err),
              std::nullopt);
    EXPECT_EQ(set.indexes, (std::vector<std::string>{"a.gdx", "b.gdx"}));
    EXPECT_EQ(set.pairs, 20);
    EXPECT_TRUE(set.table_only.at(table->flag)) << only;
  }
}

TEST(QueryBenchFlagsTest, HelpAndBadValues) {
  QueryBenchOptions options;
  const std::string help = QueryBenchFlags(&options)->help();
  EXPECT_THAT(help, HasSubstr("query_bench: constant-time query throughput, one thread."));
  EXPECT_THAT(help, HasSubstr("--field-only"));
  for (const QueryBenchTable* table : QueryBenchTables()) {
    EXPECT_THAT(help, HasSubstr("--" + table->flag + "-only"));
    EXPECT_THAT(help, HasSubstr(table->help));
  }
  auto app = QueryBenchFlags(&options);
  std::ostringstream out, err;
  EXPECT_NE(ParseFlags(*app, {"query_bench", "--pairs", "many"}, out, err).value_or(0), 0);
}

TEST(QueryBenchPointsTest, InteriorPointsAreValidAndSeeded) {
  const auto ix = SmallIndex(false);
  const auto p = InteriorPoints(*ix, 200, 3);
  ASSERT_EQ(p.size(), 200u);
  for (const mesh::SurfacePoint& x : p) {
    EXPECT_GE(x.face, 0);
    EXPECT_LT(x.face, ix->num_faces());
    for (double w : x.w) EXPECT_GE(w, 0);
    EXPECT_NEAR(x.w[0] + x.w[1] + x.w[2], 1, 1e-12);
  }
  const auto again = InteriorPoints(*ix, 200, 3);
  EXPECT_EQ(again[17].face, p[17].face);
  EXPECT_EQ(again[17].w, p[17].w);
}

TEST(QueryBenchPointsTest, VertexPointsSitAtOneCorner) {
  const auto ix = SmallIndex(false);
  for (const mesh::SurfacePoint& x : VertexPoints(*ix, 100, 4)) {
    EXPECT_LT(x.face, ix->num_faces());
    std::array<double, 3> w = x.w;
    std::sort(w.begin(), w.end());
    EXPECT_EQ(w, (std::array<double, 3>{0, 0, 1}));
  }
}

TEST(QueryBenchPointsTest, PackedMatrixIsTheSampleMatrix) {
  const auto ix = SmallIndex(false);
  const PackedMatrix packed(*ix);
  for (int32_t a = 0; a < ix->num_samples(); ++a) {
    for (int32_t b = 0; b < ix->num_samples(); ++b) {
      // A float32 copy (of the 24-bit codes, by default).
      EXPECT_EQ(packed(a, b), static_cast<float>(ix->SampleDistance(a, b))) << a << " " << b;
    }
  }
}

// `header` (title lines, then the header row and its rule) has `title_lines`
// lines before a header row as wide as `row`.
void ExpectTable(const std::string& header, size_t title_lines, const std::string& row) {
  const auto lines = Lines(header);
  ASSERT_EQ(lines.size(), title_lines + 2);
  EXPECT_EQ(Columns(lines[title_lines]), Columns(row));
  EXPECT_EQ(Columns(lines[title_lines + 1]), Columns(row));
}

TEST(QueryBenchTablesTest, ThroughputRowLayout) {
  const ThroughputFigures f{.vertices = 4608,
                            .samples = 200,
                            .vertex_rate = 5.67e6,
                            .interior_rate = 4.36e6,
                            .batch_rate = 0.16e6,
                            .unfold_batch_rate = 4.6e6,
                            .near_percent = 1.2,
                            .scalar_batch_rate = 0.16e6,
                            .gather_rate = 44.36e6,
                            .linear_rate = 4.97e6,
                            .near_path_us = 2.1,
                            .near_exact_us = 71.7,
                            .near_pairs = 1000,
                            .path_ms = 0.54,
                            .corridor_ms = 2.67,
                            .packed_gather_rate = 31.92e6};
  const std::string row = ThroughputRow("t.gdx", f);
  EXPECT_EQ(row,
            "| t.gdx | 4608 | 200 | 5.67M | 4.36M | 0.16M | 4.60M (1.20% near) | 0.16M | 44.36M | "
            "277.25 | 4.97M | 2.1 / 71.7 us (1000) | 0.54 / 2.67 ms | 31.92M (0.2 / 0.1 MiB) |");
  EXPECT_EQ(Columns(row), 14);
  ExpectTable(ThroughputHeader(), 0, row);
}

TEST(QueryBenchTablesTest, RefinementRowLayout) {
  // d<L, 500 pairs: default, pure O(1), pure O(1) on uniform pairs, with
  // bounds, tolerance 0.005, traces only.
  const RefinementFigures f{"d<L", 500, 0.679e6, 4.144e6, 4.398e6, 0.777e6, 0.1727e6, 0.219e6};
  const std::string row = RefinementRow("t.gdx", f);
  EXPECT_EQ(row,
            "| t.gdx | d<L | 500 | 0.679M | 4.144M | 0.16 | 0.15 | 0.777M | 0.1727M | 0.219M | "
            "0.05 |");
  ExpectTable(RefinementHeader(), 1, row);
  EXPECT_THAT(Lines(RefinementHeader())[0], StartsWith("Refinement (DistanceOptions)"));
}

// Every registered table prints rows as wide as its header on a small index.
TEST(QueryBenchTablesTest, RegisteredTablesRowsFitTheirHeaders) {
  const auto ix = SmallIndex(false);
  for (const QueryBenchTable* table : QueryBenchTables()) {
    ::testing::internal::CaptureStdout();
    table->run("t.gdx", ix);
    const std::vector<std::string> rows = Lines(::testing::internal::GetCapturedStdout());
    ASSERT_FALSE(rows.empty()) << table->flag;
    for (const std::string& row : rows) {
      EXPECT_THAT(row, StartsWith("| t.gdx | ")) << table->flag;
      ExpectTable(table->header(), 0, row);
    }
  }
}

TEST(QueryBenchTablesTest, FieldRowLayout) {
  const FieldFigures f{.field = "3 L", .per_field = 900, .us = 450};
  const std::string row = FieldRow("t.gdx", f);
  EXPECT_EQ(row, "| t.gdx | 3 L | 900 | 450 us | 2M |");
  ExpectTable(FieldHeader(), 0, row);
}

TEST(QueryBenchRunTest, MeasuresASmallIndex) {
  const auto ix = SmallIndex(false);
  const ThroughputFigures f = MeasureThroughput(ix, 50);
  EXPECT_EQ(f.vertices, ix->num_vertices());
  EXPECT_EQ(f.samples, 40);
  EXPECT_GT(f.batch_rate, 0);
  EXPECT_GE(f.near_percent, 0);
  EXPECT_LE(f.near_percent, 100);
  EXPECT_LE(f.near_pairs, 1000u);
}

// The whole run on a calibrated index in a file: its five tables, each row
// as wide as its header.
TEST(QueryBenchRunTest, PrintsEveryTable) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("query_bench_lib_test_" + std::to_string(getpid()) + ".gdx");
  {
    auto bytes = testing::BuildTestIndex(mesh::gen::Sphere(3, 1.0), 40, /*calibrate=*/true);
    ASSERT_TRUE(bytes.ok()) << bytes.status();
    std::ofstream(path, std::ios::binary) << *bytes;
  }
  QueryBenchOptions options{.indexes = {path.string()}, .pairs = 40};
  ::testing::internal::CaptureStdout();
  const int code = RunQueryBench(options);
  const std::string out = ::testing::internal::GetCapturedStdout();
  std::filesystem::remove(path);
  EXPECT_EQ(code, 0);
  std::vector<int> widths;
  for (const std::string& line : Lines(out)) {
    if (line[0] == '|') widths.push_back(Columns(line));
  }
  // Header and rule, one row; header and rule, uniform and four bins;
  // header and rule, vertex and interior points in four bins, uniform pairs
  // and two tolerances; then the registered tables (their rows are checked
  // above); last header and rule, four fields.
  const std::vector<int> first = {14, 14, 14, 11, 11, 11, 11, 11, 11, 11, 9, 9,
                                  9,  9,  9,  9,  9,  9,  9,  9,  9,  9,  9};
  const std::vector<int> last = {5, 5, 5, 5, 5, 5};
  ASSERT_GT(widths.size(), first.size() + last.size());
  EXPECT_EQ(std::vector<int>(widths.begin(), widths.begin() + first.size()), first);
  EXPECT_EQ(std::vector<int>(widths.end() - last.size(), widths.end()), last);
  EXPECT_THAT(out, HasSubstr("\nRefined answers against the exact engine"));
  for (const QueryBenchTable* table : QueryBenchTables()) {
    EXPECT_THAT(out, HasSubstr("\n" + table->title + "\n" + table->header()));
  }
  EXPECT_THAT(out, HasSubstr("\nDistance fields (5 interior sources, one at a time)\n"));
  EXPECT_THAT(out, HasSubstr("| whole mesh, exact | 642 |"));
}

// The field rows read their sources in the mesh file's ids: on an index
// whose builder split long edges (a coarse sphere sampled more finely than it
// has vertices) those are not the index's own faces.
TEST(QueryBenchRunTest, FieldsOfASplitIndex) {
  const mesh::Mesh coarse = mesh::gen::Sphere(1, 1.0);
  auto prepared = builder::PrepareMesh(coarse, {}, 120, /*refine=*/true);
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  builder::BuildOptions options;
  options.num_samples = 120;
  builder::BuildSummary summary;
  auto data = builder::BuildPreparedIndex(*prepared, options, &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  auto bytes = index::SerializeIndex(*data);
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  auto ix = index::Index::FromBytes(*std::move(bytes));
  ASSERT_TRUE(ix.ok()) << ix.status();
  ASSERT_GT((*ix)->split_vertices(), 0);
  ::testing::internal::CaptureStdout();
  const absl::Status status = BenchField("split", *ix);
  const std::string out = ::testing::internal::GetCapturedStdout();
  ASSERT_TRUE(status.ok()) << status;
  EXPECT_THAT(out, HasSubstr("| split | whole mesh, exact | 42 |"));
}

TEST(QueryBenchRunTest, AnIndexThatCannotBeOpenedExitsOne) {
  QueryBenchOptions options{.indexes = {"/nonexistent/x.gdx"}, .pairs = 10};
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const int code = RunQueryBench(options);
  ::testing::internal::GetCapturedStdout();
  EXPECT_THAT(::testing::internal::GetCapturedStderr(), HasSubstr("/nonexistent/x.gdx: "));
  EXPECT_EQ(code, 1);
}

}  // namespace
}  // namespace geodex::bench
