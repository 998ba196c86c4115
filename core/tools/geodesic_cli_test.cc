#include "core/tools/geodesic_cli.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_split.h"
#include "core/mesh/generators.h"
#include "core/tools/cli_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::tools {
namespace {

using ::testing::HasSubstr;
using tools::testing::Lines;
using tools::testing::ReadTestFile;

std::string WriteTestFile(const std::string& file, const std::string& text) {
  return tools::testing::WriteTestFile(tools::testing::TestDir("geodex_geodesic_cli_test"), file,
                                       text);
}
using ::testing::StartsWith;

// The flat 4x4 grid of unit cells: geodesic distance = Euclidean distance;
// vertex v sits at (v % 5, v / 5).
mesh::Mesh FlatGrid() { return mesh::gen::Grid(4, 4, 4.0, 4.0); }

double GridDistance(int32_t u, int32_t v) { return std::hypot(u % 5 - v % 5, u / 5 - v / 5); }

// The point of vertex v as a pair-file point "f w0 w1 w2".
std::string PointText(const mesh::Mesh& m, int32_t v) {
  const absl::StatusOr<mesh::SurfacePoint> p = mesh::VertexPoint(m, v);
  std::ostringstream text;
  text << p->face << " " << p->w[0] << " " << p->w[1] << " " << p->w[2];
  return text.str();
}

// FlatGrid written as OBJ.
std::string GridFile() {
  const std::string path =
      (tools::testing::TestDir("geodex_geodesic_cli_test") / "grid.obj").string();
  EXPECT_TRUE(mesh::WriteObj(FlatGrid(), path).ok());
  return path;
}

TEST(GeodesicCommandLineTest, JobFollowsTheFlags) {
  {
    GeodesicCommandLine cli;
    cli.app().parse("m.obj", false);
    EXPECT_EQ(cli.job(), GeodesicJob::kNone);
    EXPECT_EQ(cli.args().out, "-");
    EXPECT_EQ(cli.args().engine, "wavefront");
    EXPECT_EQ(cli.args().threads, common::ThreadCount(0));
  }
  {
    GeodesicCommandLine cli;
    cli.app().parse("m.stl --pairs - --threads 3 --weld 1e-6", false);
    EXPECT_EQ(cli.job(), GeodesicJob::kPairs);
    EXPECT_EQ(cli.args().mesh_path, "m.stl");
    EXPECT_EQ(cli.args().pairs_path, "-");
    EXPECT_EQ(cli.args().threads, 3);
    EXPECT_DOUBLE_EQ(cli.args().read.weld_tolerance, 1e-6);
  }
  {
    GeodesicCommandLine cli;
    cli.app().parse("m.obj --source-vertex 7 --out d.txt --engine windows --stats", false);
    EXPECT_EQ(cli.job(), GeodesicJob::kFromVertex);
    EXPECT_EQ(cli.args().source_vertex, 7);
    EXPECT_EQ(cli.args().out, "d.txt");
    EXPECT_EQ(cli.args().engine, "windows");
    EXPECT_TRUE(cli.args().stats);
  }
}

TEST(GeodesicCommandLineTest, RefusesWhatCli11Checks) {
  const auto parse = [](const std::string& line) {
    GeodesicCommandLine cli;
    cli.app().parse(line, false);
  };
  EXPECT_THROW(parse("m.obj --pairs p --source-vertex 1"), CLI::ExcludesError);
  EXPECT_THROW(parse("m.obj --pairs p --out x"), CLI::RequiresError);
  EXPECT_THROW(parse("m.obj --pairs p --stats"), CLI::RequiresError);
  EXPECT_THROW(parse("m.obj --source-vertex 1 --engine fast"), CLI::ValidationError);
  EXPECT_THROW(parse("m.obj --pairs p --threads 0"), CLI::ValidationError);
  EXPECT_THROW(parse("m.obj --pairs p --weld 2"), CLI::ValidationError);
  EXPECT_THROW(parse("--pairs p"), CLI::RequiredError);
}

TEST(GeodesicToolTest, ExactPairDistancesOnAFlatGrid) {
  const mesh::Mesh grid = FlatGrid();
  // Sources repeat (0, 12, 0, 24, 12) so that groups share propagations;
  // the answers stay in input order.
  const std::vector<std::pair<int32_t, int32_t>> ids = {{0, 24},  {12, 0},  {0, 4},
                                                        {24, 20}, {12, 12}, {0, 0}};
  std::vector<mesh::PointPair> pairs;
  for (size_t i = 0; i < ids.size(); ++i) {
    pairs.push_back({*mesh::VertexPoint(grid, ids[i].first),
                     *mesh::VertexPoint(grid, ids[i].second), static_cast<int64_t>(i + 1)});
  }
  for (int threads : {1, 3}) {
    const absl::StatusOr<std::vector<double>> d = ExactPairDistances(grid, pairs, threads);
    ASSERT_TRUE(d.ok()) << d.status();
    ASSERT_EQ(d->size(), pairs.size());
    for (size_t i = 0; i < ids.size(); ++i) {
      EXPECT_NEAR((*d)[i], GridDistance(ids[i].first, ids[i].second), 1e-12) << i;
    }
  }
}

TEST(GeodesicToolTest, PairDistancesText) {
  const mesh::Mesh grid = FlatGrid();
  GeodesicToolArgs args;
  args.mesh_path = GridFile();
  args.threads = 2;
  args.pairs_path =
      WriteTestFile("pairs.txt", PointText(grid, 0) + " " + PointText(grid, 24) + "\n# comment\n" +
                                     PointText(grid, 6) + " " + PointText(grid, 6) + "\n");
  const absl::StatusOr<std::string> out = PairDistancesText(args);
  ASSERT_TRUE(out.ok()) << out.status();
  const std::vector<std::string> lines = Lines(*out);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NEAR(std::stod(lines[0]), std::sqrt(32.0), 1e-12);
  EXPECT_EQ(lines[1], "0");
}

TEST(GeodesicToolTest, BadPairLineIsNamed) {
  GeodesicToolArgs args;
  args.mesh_path = GridFile();
  args.pairs_path = WriteTestFile("bad.txt", "0 1 0 0 5 0 1 0\n0 1 0 0 5 0 1\n");
  const absl::StatusOr<std::string> out = PairDistancesText(args);
  EXPECT_EQ(GeodesicExitCode(out.status()), 2);
  EXPECT_THAT(out.status().message(), HasSubstr("line 2"));
}

TEST(GeodesicToolTest, DistancesFromVertexToAFile) {
  GeodesicToolArgs args;
  args.mesh_path = GridFile();
  args.out = (tools::testing::TestDir("geodex_geodesic_cli_test") / "from12.txt").string();
  for (const char* engine : {"wavefront", "windows"}) {
    args.engine = engine;
    args.source_vertex = 12;
    args.stats = true;
    std::FILE* stats = std::tmpfile();
    ASSERT_NE(stats, nullptr);
    const absl::Status status = WriteDistancesFromVertex(args, stats);
    ASSERT_TRUE(status.ok()) << status;
    const std::vector<std::string> lines = Lines(ReadTestFile(args.out));
    ASSERT_EQ(lines.size(), 25u) << engine;
    for (int32_t v = 0; v < 25; ++v) {
      EXPECT_NEAR(std::stod(lines[v]), GridDistance(12, v), 1e-12) << engine << " " << v;
    }
    std::rewind(stats);
    char line[256] = {};
    ASSERT_NE(std::fgets(line, sizeof line, stats), nullptr);
    EXPECT_THAT(std::string(line), StartsWith(std::string("engine ") + engine + ": "));
    EXPECT_THAT(std::string(line), HasSubstr(" windows created, "));
    std::fclose(stats);
  }
}

TEST(GeodesicToolTest, VertexPastTheEndIsOutOfRange) {
  GeodesicToolArgs args;
  args.mesh_path = GridFile();
  args.source_vertex = 25;
  const absl::Status status = WriteDistancesFromVertex(args, nullptr);
  EXPECT_EQ(status.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(status.message(), HasSubstr("--source-vertex 25 is not a vertex of "));
  EXPECT_THAT(status.message(), HasSubstr("(it has 25 vertices, numbered from 0)"));
  EXPECT_EQ(GeodesicExitCode(status), 2);
}

TEST(GeodesicToolTest, ExitCodes) {
  EXPECT_EQ(GeodesicExitCode(absl::OkStatus()), 0);
  EXPECT_EQ(GeodesicExitCode(absl::InvalidArgumentError("x")), 2);
  EXPECT_EQ(GeodesicExitCode(absl::OutOfRangeError("x")), 2);
  EXPECT_EQ(GeodesicExitCode(absl::NotFoundError("x")), 1);
  EXPECT_EQ(GeodesicExitCode(absl::DataLossError("x")), 1);
}

}  // namespace
}  // namespace geodex::tools
