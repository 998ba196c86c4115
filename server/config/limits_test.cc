#include "server/config/limits.h"

#include <cstdint>
#include <limits>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::server {
namespace {

using ::testing::HasSubstr;

void ExpectExhausted(const absl::Status& status, const char* message) {
  EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted) << status;
  EXPECT_THAT(std::string(status.message()), HasSubstr(message));
}

TEST(LimitChecksTest, EachLimitHoldsAtItsValueAndFailsOneBeyond) {
  ServiceLimits limits;
  limits.max_pairs_per_message = 10;
  limits.max_field_sources = 3;
  limits.max_path_pairs = 4;
  limits.max_locate_positions = 5;
  limits.max_concurrent_streams = 2;
  EXPECT_TRUE(CheckPairsPerMessage(limits, 10).ok());
  ExpectExhausted(CheckPairsPerMessage(limits, 11),
                  "11 pairs exceed the limit of 10 per message (max_pairs_per_message)");
  EXPECT_TRUE(CheckFieldSources(limits, 3).ok());
  ExpectExhausted(CheckFieldSources(limits, 4),
                  "4 sources exceed the limit of 3 (max_field_sources)");
  EXPECT_TRUE(CheckPathPairs(limits, 4).ok());
  ExpectExhausted(CheckPathPairs(limits, 5),
                  "5 pairs exceed the limit of 4 per Path call (max_path_pairs)");
  EXPECT_TRUE(CheckLocatePositions(limits, 5).ok());
  ExpectExhausted(CheckLocatePositions(limits, 6),
                  "6 positions exceed the limit of 5 per Locate call (max_locate_positions)");
  EXPECT_TRUE(CheckConcurrentStreams(limits, 1).ok());
  ExpectExhausted(CheckConcurrentStreams(limits, 2),
                  "2 streaming calls already running (max_concurrent_streams)");
}

TEST(LimitChecksTest, FieldVerticesNamesTheLimitAndModelsLowerIt) {
  ServiceLimits limits;
  limits.max_field_vertices = 1000;
  ExpectExhausted(
      FieldVerticesExceeded(limits,
                            absl::ResourceExhaustedError(
                                "the field within radius 2 reaches more than 1000 vertices")),
      "the field within radius 2 reaches more than 1000 vertices, the limit (max_field_vertices)");
  ModelLimits model;
  model.set_max_field_vertices(10);
  EXPECT_EQ(WithModelLimits(limits, model).max_field_vertices, 10);
  model.set_max_field_vertices(5000);  // a model only lowers the server's
  EXPECT_EQ(WithModelLimits(limits, model).max_field_vertices, 1000);
}

TEST(LimitChecksTest, MatrixCellsWithoutOverflow) {
  ServiceLimits limits;
  limits.max_matrix_cells = 100;
  EXPECT_TRUE(CheckMatrixCells(limits, 10, 10).ok());
  EXPECT_TRUE(CheckMatrixCells(limits, 0, std::numeric_limits<int64_t>::max()).ok());
  ExpectExhausted(CheckMatrixCells(limits, 10, 11),
                  "10 sources x 11 targets exceed the limit of 100 cells (max_matrix_cells)");
  // The product would overflow int64.
  const int64_t big = int64_t{1} << 40;
  ExpectExhausted(CheckMatrixCells(limits, big, big), "(max_matrix_cells)");
}

}  // namespace
}  // namespace geodex::server
