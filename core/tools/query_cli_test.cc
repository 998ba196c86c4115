#include "core/tools/query_cli.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_split.h"
#include "core/common/file_util.h"
#include "core/mesh/generators.h"
#include "core/tools/cli_testing.h"
#include "core/build/build_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::tools {
namespace {

using ::testing::EndsWith;
using ::testing::HasSubstr;
using tools::testing::Lines;
using tools::testing::ReadTestFile;

std::string WriteTestFile(const std::string& file, const std::string& text) {
  return tools::testing::WriteTestFile(tools::testing::TestDir("geodex_query_cli_test"), file,
                                       text);
}
using ::testing::StartsWith;

// Parses `command_line` (without the program name) into a fresh
// QueryCommandLine's args; CLI11's errors are thrown.
QueryToolArgs Parse(const std::string& command_line) {
  QueryCommandLine cli;
  cli.app().parse(command_line, /*program_name_included=*/false);
  return cli.args();
}

TEST(QueryCommandLineTest, FillsTheArgs) {
  const QueryToolArgs args = Parse(
      "x.gdx --pairs p.txt --error-bounds --tolerance 0.01 --near-pairs unfold "
      "--linear-baseline");
  EXPECT_EQ(args.index, "x.gdx");
  EXPECT_EQ(args.pairs, "p.txt");
  EXPECT_TRUE(args.error_bounds);
  EXPECT_DOUBLE_EQ(args.tolerance, 0.01);
  EXPECT_EQ(args.near_pairs, "unfold");
  EXPECT_TRUE(args.baseline);
  EXPECT_FALSE(args.info);

  const QueryToolArgs expmap = Parse("x.gdx --expmap \"3 1 0 0\" --radius 0.5 --direction 1 0 0");
  EXPECT_EQ(expmap.expmap, "3 1 0 0");
  EXPECT_DOUBLE_EQ(expmap.radius, 0.5);
  EXPECT_EQ(expmap.direction, (std::vector<double>{1, 0, 0}));

  const QueryToolArgs paths = Parse("x.gdx --paths - --format json --exact-path-corridor 4");
  EXPECT_EQ(paths.paths, "-");
  EXPECT_EQ(paths.format, "json");
  EXPECT_EQ(paths.exact_path_corridor, 4);
}

TEST(QueryCommandLineTest, Defaults) {
  const QueryToolArgs args = Parse("x.gdx --info");
  EXPECT_TRUE(args.info);
  EXPECT_EQ(args.format, "xyz");
  EXPECT_EQ(args.near_pairs, "path");
  EXPECT_EQ(args.tolerance, 0);
  EXPECT_EQ(args.exact_path_corridor, 0);
}

TEST(QueryCommandLineTest, RefusesWhatCli11Checks) {
  EXPECT_THROW(Parse("--pairs p.txt"), CLI::RequiredError);
  EXPECT_THROW(Parse("x.gdx --pairs a --paths b"), CLI::ExcludesError);
  EXPECT_THROW(Parse("x.gdx --field a --locate b"), CLI::ExcludesError);
  EXPECT_THROW(Parse("x.gdx --pairs a --info"), CLI::ExcludesError);
  EXPECT_THROW(Parse("x.gdx --pairs a --near-pairs fast"), CLI::ValidationError);
  EXPECT_THROW(Parse("x.gdx --paths a --exact-path-corridor 65"), CLI::ValidationError);
  EXPECT_THROW(Parse("x.gdx --pairs a --tolerance -1"), CLI::ValidationError);
  EXPECT_THROW(Parse("x.gdx --pairs a --refine-below -1"), CLI::ValidationError);
  EXPECT_EQ(Parse("x.gdx --pairs a --refine-below 8").refine_below, 8);
  EXPECT_THROW(Parse("x.gdx --paths a --format csv"), CLI::ValidationError);
  EXPECT_THROW(Parse("x.gdx --expmap '0 1 0 0' --direction 1 0"), CLI::ArgumentMismatch);
}

TEST(QueryCommandLineTest, HelpNamesEveryQuery) {
  QueryCommandLine cli;
  const std::string help = cli.app().help();
  EXPECT_THAT(help, StartsWith("geodex-query: geodesic queries from an index file, offline."));
  for (const char* flag :
       {"--pairs", "--paths", "--field", "--locate", "--expmap", "--info", "--near-pairs",
        "--exact-near-pairs", "--error-bounds", "--tolerance", "--refine-below",
        "--exact-path-corridor",
        "--linear-baseline", "--nearest", "--format", "--radius", "--direction"}) {
    EXPECT_THAT(help, HasSubstr(flag));
  }
}

TEST(QueryToolTest, DistanceOptionsFollowTheFlags) {
  QueryToolArgs args;
  EXPECT_EQ(DistanceOptionsOf(args).near_pairs, query::NearPairs::kPath);
  args.near_pairs = "unfold";
  args.tolerance = 0.02;
  EXPECT_EQ(DistanceOptionsOf(args).near_pairs, query::NearPairs::kUnfold);
  EXPECT_EQ(DistanceOptionsOf(args).tolerance, 0.02);
  EXPECT_EQ(DistanceOptionsOf(args).refine_below_l1000, 0);
  args.refine_below = 8;
  EXPECT_EQ(DistanceOptionsOf(args).refine_below_l1000, 8);
  args.exact_near = true;  // --exact-near-pairs wins over --near-pairs
  EXPECT_EQ(DistanceOptionsOf(args).near_pairs, query::NearPairs::kExact);
  args = {};
  args.near_pairs = "exact";
  EXPECT_EQ(DistanceOptionsOf(args).near_pairs, query::NearPairs::kExact);
}

TEST(QueryToolTest, ExitCodes) {
  EXPECT_EQ(QueryExitCode(absl::OkStatus()), 0);
  EXPECT_EQ(QueryExitCode(absl::InvalidArgumentError("x")), 2);
  EXPECT_EQ(QueryExitCode(absl::OutOfRangeError("x")), 2);
  EXPECT_EQ(QueryExitCode(absl::NotFoundError("x")), 2);
  EXPECT_EQ(QueryExitCode(absl::DataLossError("x")), 1);
  EXPECT_EQ(QueryExitCode(absl::FailedPreconditionError("x")), 1);
}

// An index of a small icosphere with its calibration, as a file.
class QueryToolIndexTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    mesh_ = new mesh::Mesh(mesh::gen::Sphere(2, 1.0));
    absl::StatusOr<std::string> bytes =
        geodex::testing::BuildTestIndex(*mesh_, 40, /*calibrate=*/true);
    ASSERT_TRUE(bytes.ok()) << bytes.status();
    index_path_ =
        new std::string((tools::testing::TestDir("geodex_query_cli_test") / "sphere.gdx").string());
    ASSERT_TRUE(AtomicWriteFile(*index_path_, *bytes).ok());
  }
  static void TearDownTestSuite() {
    delete mesh_;
    delete index_path_;
  }

  QueryToolArgs Args() const {
    QueryToolArgs args;
    args.index = *index_path_;
    return args;
  }

  static mesh::Mesh* mesh_;
  static std::string* index_path_;
};
mesh::Mesh* QueryToolIndexTest::mesh_ = nullptr;
std::string* QueryToolIndexTest::index_path_ = nullptr;

TEST_F(QueryToolIndexTest, InfoCountsTheMeshFile) {
  QueryToolArgs args = Args();
  args.info = true;
  const absl::StatusOr<std::string> out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  // The report for a person: the file, the mesh file's counts, the samples.
  EXPECT_THAT(*out, HasSubstr("geodex index"));
  EXPECT_THAT(*out, HasSubstr(std::to_string(mesh_->num_vertices()) + " vertices, " +
                              std::to_string(mesh_->num_faces()) + " faces"));
  EXPECT_THAT(*out, HasSubstr("40 requested"));
  // And for a script, the same figures as JSON.
  QueryToolArgs json = Args();
  json.info = true;
  json.format = "json";
  const absl::StatusOr<std::string> object = AnswerQueryTool(json);
  ASSERT_TRUE(object.ok()) << object.status();
  EXPECT_THAT(*object, StartsWith("{"));
  EXPECT_THAT(*object, HasSubstr("\"vertices\": " + std::to_string(mesh_->num_vertices())));
  EXPECT_THAT(*object, HasSubstr("\"requested\": 40"));
}

TEST_F(QueryToolIndexTest, NoQueryIsInvalid) {
  const absl::StatusOr<std::string> out = AnswerQueryTool(Args());
  EXPECT_EQ(out.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(out.status().message(), HasSubstr("give one of --pairs"));
}

TEST_F(QueryToolIndexTest, MissingIndexIsAnError) {
  QueryToolArgs args = Args();
  args.index = (tools::testing::TestDir("geodex_query_cli_test") / "no_such.gdx").string();
  args.info = true;
  EXPECT_FALSE(AnswerQueryTool(args).ok());
}

TEST_F(QueryToolIndexTest, PairDistancesInInputOrder) {
  QueryToolArgs args = Args();
  args.pairs =
      WriteTestFile("pairs.txt", "0 1 0 0 0 1 0 0\n# comment\n3 0.2 0.3 0.5 60 0.3 0.3 0.4\n");
  absl::StatusOr<std::string> out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  std::vector<std::string> lines = Lines(*out);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "0");
  EXPECT_GT(std::stod(lines[1]), 0);
  EXPECT_LT(std::stod(lines[1]), M_PI);  // within half the unit sphere's great circle

  args.error_bounds = true;
  out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  lines = Lines(*out);
  ASSERT_EQ(lines.size(), 2u);
  for (const std::string& line : lines) {
    EXPECT_EQ(std::vector<std::string>(absl::StrSplit(line, ' ')).size(), 2u) << line;
  }

  args.error_bounds = false;
  args.baseline = true;
  out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  EXPECT_EQ(Lines(*out).size(), 2u);
}

TEST_F(QueryToolIndexTest, BadPairNamesItsLine) {
  QueryToolArgs args = Args();
  args.pairs = WriteTestFile("bad_pairs.txt", "0 1 0 0 1 1 0 0\n0 1 0 0 99999 1 0 0\n");
  const absl::StatusOr<std::string> out = AnswerQueryTool(args);
  EXPECT_EQ(QueryExitCode(out.status()), 2);
  EXPECT_THAT(out.status().message(), HasSubstr("line 2"));
}

TEST_F(QueryToolIndexTest, PathsAsXyzAndJson) {
  QueryToolArgs args = Args();
  args.paths = WriteTestFile("path_pairs.txt", "0 1 0 0 60 0.3 0.3 0.4\n5 0 1 0 7 0 0 1\n");
  absl::StatusOr<std::string> out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  // Two paths, each its length, its points and a blank line; the length is
  // the sum of the segments between the points printed.
  EXPECT_THAT(*out, StartsWith("# path 0 length "));
  EXPECT_THAT(*out, HasSubstr("\n\n# path 1 length "));
  EXPECT_THAT(*out, EndsWith("\n\n"));
  const size_t line_ends = std::count(out->begin(), out->end(), '\n');
  EXPECT_EQ(line_ends, Lines(*out).size() + 2);
  std::istringstream text(*out);
  std::string line;
  std::getline(text, line);
  const double stated = std::stod(line.substr(std::string("# path 0 length ").size()));
  double summed = 0;
  std::optional<mesh::Vec3> last;
  while (std::getline(text, line) && !line.empty()) {
    std::istringstream xyz(line);
    mesh::Vec3 p;
    xyz >> p.x() >> p.y() >> p.z();
    if (last) summed += (p - *last).norm();
    last = p;
  }
  EXPECT_GT(stated, 0);
  EXPECT_NEAR(stated, summed, 1e-12 * stated);

  args.format = "json";
  out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  EXPECT_THAT(*out, StartsWith("[\n  {\"length\": "));
  EXPECT_THAT(*out, HasSubstr(", \"points\": [{\"face\": 0, \"w\": [1, 0, 0], \"xyz\": ["));
  EXPECT_THAT(*out, HasSubstr("}]},\n  {\"length\": "));
  EXPECT_THAT(*out, EndsWith("}]}\n]\n"));
}

TEST_F(QueryToolIndexTest, FieldHasALinePerVertex) {
  QueryToolArgs args = Args();
  args.field = WriteTestFile("sources.txt", "0 1 0 0\n");
  args.nearest = true;
  const absl::StatusOr<std::string> out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  const std::vector<std::string> lines = Lines(*out);
  ASSERT_EQ(lines.size(), static_cast<size_t>(mesh_->num_vertices()));
  for (const std::string& line : lines) EXPECT_THAT(line, EndsWith(" 0"));
}

TEST_F(QueryToolIndexTest, FieldWithinARadiusListsTheVerticesWithinIt) {
  QueryToolArgs args = Args();
  args.field = WriteTestFile("sources.txt", "0 1 0 0\n");
  args.radius = 0.5;
  const absl::StatusOr<std::string> out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  const std::vector<std::string> lines = Lines(*out);
  ASSERT_FALSE(lines.empty());
  ASSERT_LT(lines.size(), static_cast<size_t>(mesh_->num_vertices()));
  int previous = -1;
  for (const std::string& line : lines) {
    const std::vector<std::string> fields = absl::StrSplit(line, ' ');
    ASSERT_EQ(fields.size(), 2u) << line;
    EXPECT_GT(std::stoi(fields[0]), previous);
    previous = std::stoi(fields[0]);
    EXPECT_LE(std::stod(fields[1]), 0.5);
  }
  args.radius = -1;
  EXPECT_EQ(AnswerQueryTool(args).status().code(), absl::StatusCode::kInvalidArgument);
  args.field.clear();
  args.locate = args.index;
  args.radius = 1;
  EXPECT_EQ(AnswerQueryTool(args).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(QueryToolIndexTest, LocateFindsAVertex) {
  QueryToolArgs args = Args();
  const mesh::Vec3 p = mesh_->position(0);
  std::ostringstream text;
  text.precision(17);
  text << p.x() << " " << p.y() << " " << p.z() << "\n" << 2 * p.x() << " 0 0\n";
  args.locate = WriteTestFile("points.txt", text.str());
  const absl::StatusOr<std::string> out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  const std::vector<std::string> lines = Lines(*out);
  ASSERT_EQ(lines.size(), 2u);
  const std::vector<std::string> first = absl::StrSplit(lines[0], ' ');
  ASSERT_EQ(first.size(), 5u);
  EXPECT_LT(std::stod(first[4]), 1e-12);  // the distance to the surface
}

TEST_F(QueryToolIndexTest, ExpMapCentreMustBeAFaceAndWeights) {
  QueryToolArgs args = Args();
  for (const char* bad : {"1 0 0", "1.5 1 0 0", "3e9 1 0 0", "0 1 0 0\n1 1 0 0", "x"}) {
    args.expmap = bad;
    const absl::StatusOr<std::string> out = AnswerQueryTool(args);
    EXPECT_EQ(out.status().code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(out.status().message(), HasSubstr("--expmap wants \"F W0 W1 W2\"")) << bad;
  }
}

TEST_F(QueryToolIndexTest, ExpMapListsVerticesWithinTheRadius) {
  QueryToolArgs args = Args();
  args.expmap = "0 1 0 0";
  args.radius = 0.6;
  const absl::StatusOr<std::string> out = AnswerQueryTool(args);
  ASSERT_TRUE(out.ok()) << out.status();
  const std::vector<std::string> lines = Lines(*out);
  ASSERT_GT(lines.size(), 1u);
  int previous = -1;
  for (const std::string& line : lines) {
    const std::vector<std::string> fields = absl::StrSplit(line, ' ');
    ASSERT_EQ(fields.size(), 3u) << line;
    const int vertex = std::stoi(fields[0]);
    EXPECT_GT(vertex, previous);  // ascending by vertex id
    previous = vertex;
    EXPECT_LE(std::hypot(std::stod(fields[1]), std::stod(fields[2])), 0.6 + 1e-9);
  }
}

}  // namespace
}  // namespace geodex::tools
