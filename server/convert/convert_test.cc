#include "server/convert/convert.h"

#include <array>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"
#include "core/index/index_report.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/model_repository_testing.h"

namespace geodex::server {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

class ConvertTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto index = index::Index::FromBytes(testing::SphereIndexBytes());
    ASSERT_TRUE(index.ok()) << index.status();
    auto queries = query::InputQueries::Create(*index);
    ASSERT_TRUE(queries.ok()) << queries.status();
    queries_ = *queries;
  }
  v1::SurfacePoints Points(std::vector<int32_t> faces, std::vector<double> weights) {
    v1::SurfacePoints p;
    for (int32_t f : faces) p.add_faces(f);
    for (double w : weights) p.add_weights(w);
    return p;
  }
  absl::Status Read(const v1::SurfacePoints& p, const char* name = "a") {
    return PointsFromProto(p, name, *queries_, &out_);
  }
  std::shared_ptr<const query::InputQueries> queries_;
  query::EnginePoints out_;
};

TEST_F(ConvertTest, ReadsValidPoints) {
  ASSERT_TRUE(Read(Points({0, 5}, {1, 0, 0, 0.25, 0.25, 0.5})).ok());
  ASSERT_EQ(out_.size(), 2u);
  // Read point by point, the same points answer the same.
  query::EnginePoints p, q;
  const std::vector<query::SurfacePoint> input = {{0, {1, 0, 0}}, {5, {0.25, 0.25, 0.5}}};
  ASSERT_TRUE(queries_->Read(std::span(input).first(1), query::Named("p"), &p).ok());
  ASSERT_TRUE(queries_->Read(std::span(input).last(1), query::Named("q"), &q).ok());
  const absl::StatusOr<double> want = queries_->Distance(p, 0, q, 0);
  ASSERT_TRUE(want.ok()) << want.status();
  EXPECT_EQ(*queries_->Distance(out_, 0, out_, 1), *want);
}

TEST_F(ConvertTest, NamesTheOffendingPoint) {
  const int32_t n = queries_->index().num_faces();
  absl::Status s = Read(Points({0, 99999}, {1, 0, 0, 1, 0, 0}));
  EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(std::string(s.message()),
            absl::StrFormat("a[1]: face id 99999 out of range [0, %d)", n));
  s = Read(Points({-1}, {1, 0, 0}), "b");
  EXPECT_EQ(s.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(std::string(s.message()), StartsWith("b[0]: face id -1"));

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const auto& [weights, what] :
       std::vector<std::pair<std::vector<double>, const char*>>{{{nan, 0.5, 0.5}, "not finite"},
                                                                {{inf, 0, 0}, "not finite"},
                                                                {{1.5, -0.5, 0}, "negative"},
                                                                {{0.5, 0.2, 0.2}, "sum to"}}) {
    std::vector<double> w = {1, 0, 0};
    w.insert(w.end(), weights.begin(), weights.end());
    s = Read(Points({0, 3}, w));
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << what;
    EXPECT_THAT(std::string(s.message()), StartsWith("a[1]: ")) << what;
    EXPECT_THAT(std::string(s.message()), HasSubstr(what));
  }
}

TEST_F(ConvertTest, WeightsMustBeThreePerFace) {
  absl::Status s = Read(Points({0, 1}, {1, 0, 0, 1, 0}));
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(std::string(s.message()), "a: 2 faces but 5 weights (want 6)");
}

TEST_F(ConvertTest, WeightsWithinToleranceAreAccepted) {
  EXPECT_TRUE(Read(Points({0}, {1 + 5e-7, -5e-7, 0})).ok());
}

TEST(ConvertPairsTest, PointsMustPairUp) {
  v1::SurfacePoints a, b;
  for (int32_t f : {0, 1, 2}) a.add_faces(f);
  for (int32_t f : {0, 1}) b.add_faces(f);
  const absl::Status s = CheckPairedUp(a, b);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(std::string(s.message()), "a has 3 points but b has 2; they must pair up");
  b.add_faces(2);
  EXPECT_TRUE(CheckPairedUp(a, b).ok());
}

TEST_F(ConvertTest, OnePointIsRead) {
  absl::Status status =
      OnePointFromProto(Points({5}, {0.25, 0.25, 0.5}), "center", *queries_, &out_);
  ASSERT_TRUE(status.ok()) << status;
  EXPECT_EQ(out_.size(), 1u);
  for (const v1::SurfacePoints& points : {Points({}, {}), Points({0, 1}, {1, 0, 0, 1, 0, 0})}) {
    status = OnePointFromProto(points, "center", *queries_, &out_);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(std::string(status.message()),
              absl::StrFormat("center: give exactly one point, got %d", points.faces_size()));
  }
  status = OnePointFromProto(Points({99999}, {1, 0, 0}), "center", *queries_, &out_);
  EXPECT_EQ(status.code(), absl::StatusCode::kOutOfRange);
  EXPECT_THAT(std::string(status.message()), StartsWith("center[0]: face id 99999"));
}

TEST(ConvertMatrixTest, BlockCarriesValuesAndBoundsRowMajor) {
  const std::vector<double> values = {1, 2, 3, 4, 5, 6};
  const std::vector<double> bounds = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  v1::MatrixBlock block;
  MatrixBlockToProto(4, 2, 3, values, bounds, 7, &block);
  EXPECT_EQ(block.row_offset(), 4);
  EXPECT_EQ(block.rows(), 2);
  EXPECT_EQ(block.num_targets(), 3);
  EXPECT_EQ(block.version(), 7);
  EXPECT_THAT(block.values(), ::testing::ElementsAreArray(values));
  EXPECT_THAT(block.bounds(), ::testing::ElementsAreArray(bounds));
  // A reused block without bounds has none left from the last one.
  MatrixBlockToProto(6, 1, 3, std::span<const double>(values).first(3), {}, 7, &block);
  EXPECT_EQ(block.values_size(), 3);
  EXPECT_EQ(block.bounds_size(), 0);
}

TEST(ConvertPositionsTest, ChecksShapeAndFiniteness) {
  std::vector<mesh::Vec3> out;
  v1::Positions p;
  for (double x : {0.0, 1.0, 2.0, 3.0}) p.add_xyz(x);
  EXPECT_EQ(std::string(PositionsFromProto(p, "positions", &out).message()),
            "positions: 4 coordinates, not a multiple of 3");
  p.add_xyz(std::nan(""));
  p.add_xyz(5);
  absl::Status s = PositionsFromProto(p, "positions", &out);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()), StartsWith("positions[1]: y is nan"));
  p.set_xyz(4, 4);
  ASSERT_TRUE(PositionsFromProto(p, "positions", &out).ok());
  EXPECT_EQ(out[1], mesh::Vec3(3, 4, 5));
}

TEST(ConvertPathTest, LengthIsTheSumOfSegments) {
  std::vector<query::PathPoint> path(3);
  path[0].position = {0, 0, 0};
  path[1].position = {3, 4, 0};
  path[2].position = {3, 4, 1};
  v1::Polyline line;
  PathToProto(path, &line);
  EXPECT_DOUBLE_EQ(line.length(), 6);
  EXPECT_EQ(line.points().faces_size(), 3);
  EXPECT_EQ(line.positions().xyz_size(), 9);
  UnreachablePathToProto(&line);
  EXPECT_TRUE(std::isinf(line.length()));
  EXPECT_EQ(line.points().faces_size(), 0);
}

TEST_F(ConvertTest, MeshChunkIsASliceOfTheIndexMesh) {
  const index::Index& ix = queries_->index();
  v1::MeshChunk chunk;
  MeshChunkToProto(*queries_, 10, 5, 100, 4, 3, &chunk);
  EXPECT_EQ(chunk.num_vertices(), static_cast<uint32_t>(ix.num_vertices()));
  EXPECT_EQ(chunk.num_faces(), static_cast<uint32_t>(ix.num_faces()));
  EXPECT_EQ(chunk.version(), 3);
  EXPECT_EQ(chunk.vertex_offset(), 10u);
  EXPECT_EQ(chunk.face_offset(), 100u);
  ASSERT_EQ(chunk.positions_size(), 15);
  for (int i = 0; i < 15; ++i) EXPECT_EQ(chunk.positions(i), ix.positions()[30 + i]);
  ASSERT_EQ(chunk.faces_size(), 12);
  for (int i = 0; i < 12; ++i)
    EXPECT_EQ(chunk.faces(i), static_cast<uint32_t>(ix.faces()[300 + i]));

  // Empty ranges at the end, as in the last chunks of a mesh with more faces
  // than vertices; a reused message is overwritten.
  MeshChunkToProto(*queries_, ix.num_vertices(), 0, ix.num_faces() - 1, 1, 3, &chunk);
  EXPECT_EQ(chunk.vertex_offset(), static_cast<uint32_t>(ix.num_vertices()));
  EXPECT_EQ(chunk.positions_size(), 0);
  EXPECT_EQ(chunk.faces_size(), 3);
}

TEST(ConvertModelInfoTest, DescribesAServedVersion) {
  testing::TempDir dir;
  testing::WriteModelVersion(dir.path(), "sphere", 3, testing::SphereIndexBytes());
  const std::string path = dir.path() + "/sphere/3/index.gdx";
  auto served = ServedVersion::Load(3, path, FileId{});
  ASSERT_TRUE(served.ok()) << served.status();
  ModelSnapshot model;
  model.name = "sphere";
  model.state = LoadState::kServing;
  model.available_versions = {3};
  v1::ModelInfo info;
  ModelInfoToProto(model, served->get(), &info);
  const index::Index& ix = (*served)->index();
  EXPECT_EQ(info.name(), "sphere");
  EXPECT_EQ(info.version(), 3);
  EXPECT_EQ(info.state(), v1::ModelInfo::SERVING);
  EXPECT_EQ(info.num_vertices(), ix.num_vertices());
  EXPECT_EQ(info.num_faces(), ix.num_faces());
  EXPECT_EQ(info.num_samples(), ix.num_samples());
  EXPECT_EQ(info.num_triangles(), ix.num_triangles());
  EXPECT_EQ(info.requested_samples(), 40);
  EXPECT_EQ(info.mapped_bytes(), static_cast<int64_t>(testing::SphereIndexBytes().size()));
  EXPECT_EQ(info.mesh_hash(), ix.header().mesh_hash);
  ASSERT_EQ(info.bbox_min_size(), 3);
  EXPECT_NEAR(info.bbox_min(0), -1, 1e-9);
  EXPECT_NEAR(info.bbox_max(2), 1, 1e-9);
  EXPECT_FALSE(info.builder_version().empty());
  EXPECT_FALSE(info.build_report().empty());
  for (const auto& [key, value] : info.build_report()) {
    EXPECT_FALSE(key.empty());
    EXPECT_EQ(key.find(' '), std::string::npos) << key;
  }
  // The report's JSON is the core's, for the served index.
  EXPECT_EQ(info.report_json(), index::IndexReportJson(index::MakeIndexReport(ix)));
  EXPECT_THAT(info.report_json(), HasSubstr("\"samples\": {\"requested\": 40,"));
}

// --- Options ------------------------------------------------------------------

ModelConfig Config(bool exact, bool unfold, double tolerance = 0, int corridor = 0) {
  ModelConfig config;
  config.set_exact_near_pairs(exact);
  config.set_unfold_near_pairs(unfold);
  config.set_tolerance(tolerance);
  config.set_exact_path_corridor(corridor);
  return config;
}

query::NearPairs ModeOf(const ModelConfig& config, int near_pairs, bool exact = false) {
  absl::StatusOr<query::DistanceOptions> options =
      DistanceOptionsFor(config, {.near_pairs = near_pairs, .exact_near_pairs = exact});
  EXPECT_TRUE(options.ok()) << options.status();
  return options.ok() ? options->near_pairs : query::NearPairs::kPath;
}

TEST(DistanceOptionsForTest, TheRequestsModeWinsOverTheConfiguration) {
  for (const ModelConfig& config :
       {Config(false, false), Config(true, false), Config(false, true)}) {
    EXPECT_EQ(ModeOf(config, v1::NEAR_PAIRS_PATH), query::NearPairs::kPath);
    EXPECT_EQ(ModeOf(config, v1::NEAR_PAIRS_UNFOLD), query::NearPairs::kUnfold);
    EXPECT_EQ(ModeOf(config, v1::NEAR_PAIRS_EXACT), query::NearPairs::kExact);
    EXPECT_EQ(ModeOf(config, v1::NEAR_PAIRS_UNSPECIFIED, /*exact=*/true), query::NearPairs::kExact);
    EXPECT_EQ(ModeOf(config, v1::NEAR_PAIRS_EXACT, /*exact=*/true), query::NearPairs::kExact);
  }
}

TEST(DistanceOptionsForTest, UnspecifiedTakesTheConfigurationsMode) {
  EXPECT_EQ(ModeOf(Config(false, false), v1::NEAR_PAIRS_UNSPECIFIED), query::NearPairs::kPath);
  EXPECT_EQ(ModeOf(Config(false, true), v1::NEAR_PAIRS_UNSPECIFIED), query::NearPairs::kUnfold);
  EXPECT_EQ(ModeOf(Config(true, false), v1::NEAR_PAIRS_UNSPECIFIED), query::NearPairs::kExact);
  // exact_near_pairs comes before unfold_near_pairs.
  EXPECT_EQ(ModeOf(Config(true, true), v1::NEAR_PAIRS_UNSPECIFIED), query::NearPairs::kExact);
}

TEST(DistanceOptionsForTest, ToleranceIsTheRequestsElseTheConfigurations) {
  const ModelConfig config = Config(false, false, 0.01);
  auto options = DistanceOptionsFor(config, {.tolerance = 0.002});
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->tolerance, 0.002);
  options = DistanceOptionsFor(config, {});
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->tolerance, 0.01);
  options = DistanceOptionsFor(Config(false, false), {});
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->tolerance, 0);
}

TEST(DistanceOptionsForTest, RefusesUnknownContradictoryAndBadChoices) {
  const ModelConfig config;
  auto options = DistanceOptionsFor(config, {.near_pairs = 17});
  EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(options.status().message()),
              HasSubstr("near_pairs has the unknown value 17"));
  for (int mode : {v1::NEAR_PAIRS_PATH, v1::NEAR_PAIRS_UNFOLD}) {
    options = DistanceOptionsFor(config, {.near_pairs = mode, .exact_near_pairs = true});
    EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(std::string(options.status().message()),
                HasSubstr("exact_near_pairs contradicts near_pairs = NEAR_PAIRS_"));
  }
  for (double bad :
       {-0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    options = DistanceOptionsFor(config, {.tolerance = bad});
    EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(std::string(options.status().message()),
                HasSubstr("tolerance must be finite and >= 0"));
    options = DistanceOptionsFor(config, {.refine_below = bad});
    EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(std::string(options.status().message()),
                HasSubstr("refine_below must be finite and >= 0"));
  }
  options = DistanceOptionsFor(config, {.refine_below = 8});
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->refine_below_l1000, 8);
}

TEST(DistanceChoiceTest, ReadsEachRequestsFields) {
  v1::DistanceRequest distance;
  distance.set_near_pairs(v1::NEAR_PAIRS_UNFOLD);
  distance.set_exact_near_pairs(true);
  distance.set_tolerance(0.5);
  distance.set_error_bounds(true);
  distance.set_refine_below(8);
  DistanceChoice c = DistanceChoice::Of(distance);
  EXPECT_EQ(c.refine_below, 8);
  EXPECT_EQ(c.near_pairs, v1::NEAR_PAIRS_UNFOLD);
  EXPECT_TRUE(c.exact_near_pairs);
  EXPECT_EQ(c.tolerance, 0.5);
  EXPECT_TRUE(c.error_bounds);

  v1::DistanceBatch batch;
  batch.set_exact_near_pairs(true);
  batch.set_tolerance(0.25);
  batch.set_refine_below(4);
  c = DistanceChoice::Of(batch);
  EXPECT_EQ(c.refine_below, 4);
  EXPECT_TRUE(c.exact_near_pairs);
  EXPECT_EQ(c.tolerance, 0.25);
  EXPECT_FALSE(c.error_bounds);

  v1::MatrixRequest matrix;
  matrix.set_near_pairs(v1::NEAR_PAIRS_EXACT);
  matrix.set_error_bounds(true);
  matrix.set_refine_below(16);
  c = DistanceChoice::Of(matrix);
  EXPECT_EQ(c.refine_below, 16);
  EXPECT_EQ(c.near_pairs, v1::NEAR_PAIRS_EXACT);
  EXPECT_FALSE(c.exact_near_pairs);
  EXPECT_TRUE(c.error_bounds);
}

TEST(PathCorridorForTest, TheRequestsElseTheConfigurationsClamped) {
  v1::PathRequest request;
  EXPECT_EQ(PathCorridorFor(Config(false, false, 0, 0), request).value(), 0);
  EXPECT_EQ(PathCorridorFor(Config(false, false, 0, 5), request).value(), 5);
  EXPECT_EQ(PathCorridorFor(Config(false, false, 0, 1000), request).value(), kMaxPathCorridor);
  EXPECT_EQ(PathCorridorFor(Config(false, false, 0, -3), request).value(), 0);
  request.set_exact_corridor(7);
  EXPECT_EQ(PathCorridorFor(Config(false, false, 0, 5), request).value(), 7);
  request.set_exact_corridor(kMaxPathCorridor);
  EXPECT_EQ(PathCorridorFor(ModelConfig(), request).value(), kMaxPathCorridor);
  request.set_exact_corridor(kMaxPathCorridor + 1);
  const auto corridor = PathCorridorFor(ModelConfig(), request);
  EXPECT_EQ(corridor.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(corridor.status().message()), HasSubstr("exact_corridor 65 exceeds 64"));
}

}  // namespace
}  // namespace geodex::server
