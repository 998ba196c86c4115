#include "core/query/engine/internal/bounds/error_bounds.h"

#include <cmath>

#include "core/builder/builder.h"
#include "core/mesh/generators.h"
#include "gtest/gtest.h"

namespace geodex::query {
namespace {

// The index of a small grid with a hand-made calibration: bound b + 1 in
// bin b for O(1) vertex pairs, 10 (b + 1) for other pairs; traces 100 + b
// and up.
std::shared_ptr<const index::Index> CalibratedGrid(bool spread) {
  builder::BuildOptions options;
  options.num_samples = 12;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data =
      builder::BuildIndex(mesh::gen::Grid(8, 8, 1, 1), options, &summary);
  if (!data.ok()) throw std::runtime_error(data.status().ToString());
  index::AccuracyRecord record{};
  record.scale_length = 0.5f;
  for (int b = 0; b < index::kAccuracyBins; ++b) {
    record.unfold_bound[0][b] = b + 1;
    record.unfold_bound[1][b] = 10 * (b + 1);
    for (int k = 0; k < 4; ++k) record.trace_bound[k][b] = 100 * (k + 1) + b;
  }
  data->accuracy = {record};
  if (spread) {
    index::SpreadBoundRecord s{};
    for (int k = 0; k < 2; ++k) {
      for (int b = 0; b < index::kAccuracyBins; ++b) {
        s.epsilon[k][b] = 0.01f;
        s.factor[k][b] = 2;
      }
    }
    // Bin 4 of other pairs keeps its constant bound.
    s.epsilon[1][4] = 0;
    s.factor[1][4] = 0;
    data->spread_bounds = {s};
  }
  absl::StatusOr<std::string> bytes = index::SerializeIndex(*data);
  if (!bytes.ok()) throw std::runtime_error(bytes.status().ToString());
  absl::StatusOr<std::shared_ptr<const index::Index>> ix = index::Index::FromBytes(*bytes);
  if (!ix.ok()) throw std::runtime_error(ix.status().ToString());
  return *ix;
}

TEST(ErrorBoundsTest, BoundsComeFromTheBinOfTheDistance) {
  const auto index = CalibratedGrid(/*spread=*/false);
  const ErrorBounds bounds(*index);
  ASSERT_TRUE(bounds.available());
  EXPECT_FALSE(bounds.has_spread());
  // L = 0.5; bins end at 0.5, 1, 2, 3, 5, 10, 20 L.
  EXPECT_EQ(bounds.Of(AnswerKind::kUnfold, true, 0.1), 1);  // 0.2 L: bin 0
  EXPECT_EQ(bounds.Of(AnswerKind::kUnfold, false, 0.1), 10);
  EXPECT_EQ(bounds.Of(AnswerKind::kUnfold, true, 0.75), 3);   // 1.5 L: bin 2
  EXPECT_EQ(bounds.Of(AnswerKind::kUnfold, true, 1.5), 5);    // 3 L: bin 4
  EXPECT_EQ(bounds.Of(AnswerKind::kUnfold, true, 1000), 8);   // the last bin
  EXPECT_EQ(bounds.Of(AnswerKind::kTrace, false, 0.1), 100);  // trace_bound[0]
  EXPECT_EQ(bounds.Of(AnswerKind::kWrappedTrace, false, 0.1), 200);
  EXPECT_EQ(bounds.Of(AnswerKind::kTrace, true, 0.1), 300);
  EXPECT_EQ(bounds.Of(AnswerKind::kWrappedTrace, true, 0.1), 400);
  EXPECT_EQ(bounds.Of(AnswerKind::kExact, true, 0.1), kExactRelativeBound * 0.1);
  EXPECT_EQ(bounds.Of(AnswerKind::kUnfold, true, INFINITY), 0);  // unreachable: exact
  // The margin beyond 3L: the larger O(1) bound of bin [3L, 5L).
  EXPECT_EQ(bounds.RefineMargin(), 50);
}

TEST(ErrorBoundsTest, SpreadScalesTheO1Bound) {
  const auto index = CalibratedGrid(/*spread=*/true);
  const ErrorBounds bounds(*index);
  ASSERT_TRUE(bounds.has_spread());
  // factor * (spread + epsilon * d) = 2 * (0.3 + 0.01 * 1).
  EXPECT_FLOAT_EQ(bounds.Of(AnswerKind::kUnfold, false, 1, 0.3), 2 * (0.3 + 0.01f * 1));
  // A factor of 0: the bin's constant bound (d = 2 = 4 L, bin 4).
  EXPECT_EQ(bounds.Of(AnswerKind::kUnfold, false, 2, 0.3), 50);
  EXPECT_FLOAT_EQ(bounds.Of(AnswerKind::kUnfold, true, 2, 0.3), 2 * (0.3 + 0.01f * 2));
  EXPECT_EQ(bounds.Of(AnswerKind::kTrace, false, 0.1), 100);  // traces keep theirs
}

TEST(ErrorBoundsTest, WithoutCalibrationThereAreNoBounds) {
  builder::BuildOptions options;
  options.num_samples = 12;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data =
      builder::BuildIndex(mesh::gen::Grid(8, 8, 1, 1), options, &summary);
  ASSERT_TRUE(data.ok()) << data.status();
  auto index = index::Index::FromBytes(*index::SerializeIndex(*data));
  ASSERT_TRUE(index.ok()) << index.status();
  const ErrorBounds bounds(**index);
  EXPECT_FALSE(bounds.available());
  EXPECT_TRUE(std::isnan(bounds.Of(AnswerKind::kUnfold, true, 0.1)));
  EXPECT_EQ(bounds.RefineMargin(), 0);
  EXPECT_TRUE(bounds.CheckOptions({}, /*bounds=*/false).ok());
  EXPECT_EQ(bounds.CheckOptions({}, /*bounds=*/true).code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(bounds.CheckOptions({.tolerance = 0.01}, false).code(),
            absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(bounds.CheckOptions({.tolerance = -1}, false).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(bounds.CheckOptions({.tolerance = NAN}, false).code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace geodex::query
