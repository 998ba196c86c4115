#include "server/convert/convert_options.h"

#include <cmath>
#include <limits>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::server {
namespace {

using ::testing::HasSubstr;

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
  for (double tolerance :
       {-0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    options = DistanceOptionsFor(config, {.tolerance = tolerance});
    EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << tolerance;
    EXPECT_THAT(std::string(options.status().message()),
                HasSubstr("tolerance must be finite and >= 0"));
  }
}

TEST(DistanceChoiceTest, ReadsEachRequestsFields) {
  v1::DistanceRequest distance;
  distance.set_near_pairs(v1::NEAR_PAIRS_UNFOLD);
  distance.set_exact_near_pairs(true);
  distance.set_tolerance(0.5);
  distance.set_error_bounds(true);
  DistanceChoice c = DistanceChoice::Of(distance);
  EXPECT_EQ(c.near_pairs, v1::NEAR_PAIRS_UNFOLD);
  EXPECT_TRUE(c.exact_near_pairs);
  EXPECT_EQ(c.tolerance, 0.5);
  EXPECT_TRUE(c.error_bounds);

  v1::DistanceBatch batch;
  batch.set_exact_near_pairs(true);
  batch.set_tolerance(0.25);
  c = DistanceChoice::Of(batch);
  EXPECT_TRUE(c.exact_near_pairs);
  EXPECT_EQ(c.tolerance, 0.25);
  EXPECT_FALSE(c.error_bounds);

  v1::MatrixRequest matrix;
  matrix.set_near_pairs(v1::NEAR_PAIRS_EXACT);
  matrix.set_error_bounds(true);
  c = DistanceChoice::Of(matrix);
  EXPECT_EQ(c.near_pairs, v1::NEAR_PAIRS_EXACT);
  EXPECT_FALSE(c.exact_near_pairs);
  EXPECT_TRUE(c.error_bounds);
}

TEST(ExpMapOptionsForTest, RadiusDirectionAndDistanceOptions) {
  v1::ExpMapRequest request;
  request.set_radius(0.75);
  request.set_near_pairs(v1::NEAR_PAIRS_UNFOLD);
  for (double x : {0.3, -1.0, 0.2}) request.mutable_reference_direction()->add_xyz(x);
  auto options = ExpMapOptionsFor(Config(false, false, 0.01), request);
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->radius, 0.75);
  ASSERT_TRUE(options->reference_direction.has_value());
  EXPECT_EQ(options->reference_direction->x(), 0.3);
  EXPECT_EQ(options->reference_direction->y(), -1.0);
  EXPECT_EQ(options->reference_direction->z(), 0.2);
  EXPECT_EQ(options->distance.near_pairs, query::NearPairs::kUnfold);
  EXPECT_EQ(options->distance.tolerance, 0.01);

  request.clear_reference_direction();
  options = ExpMapOptionsFor(ModelConfig(), request);
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_FALSE(options->reference_direction.has_value());
}

TEST(ExpMapOptionsForTest, RefusesADirectionOfOtherThanThreeNumbers) {
  v1::ExpMapRequest request;
  for (double x : {1.0, 0.0}) request.mutable_reference_direction()->add_xyz(x);
  auto options = ExpMapOptionsFor(ModelConfig(), request);
  EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(options.status().message()),
              HasSubstr("reference_direction: give one direction (3 numbers), got 2 numbers"));
  request.clear_reference_direction();
  request.set_tolerance(-1);
  EXPECT_EQ(ExpMapOptionsFor(ModelConfig(), request).status().code(),
            absl::StatusCode::kInvalidArgument);
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
