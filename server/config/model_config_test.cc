#include "server/config/model_config.h"

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/config/limits.h"
#include "server/model_repository_testing.h"

namespace geodex::server {
namespace {

using ::testing::HasSubstr;

TEST(ModelNameTest, AcceptsPlainNames) {
  for (const char* name : {"bunny", "Bunny_2", "a.b-c", "x", "v1.0"}) {
    EXPECT_TRUE(ValidateModelName(name).ok()) << name;
  }
}

TEST(ModelNameTest, RejectsNamesThatCouldEscapeTheRepository) {
  for (const char* name : {"", ".", "..", "../etc", "a/b", "/abs", ".hidden", "a..b", "a b", "a\\b",
                           "caf\xc3\xa9", "a\nb"}) {
    const absl::Status s = ValidateModelName(name);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << name;
  }
  EXPECT_FALSE(ValidateModelName(std::string(kMaxModelNameLength + 1, 'a')).ok());
  EXPECT_TRUE(ValidateModelName(std::string(kMaxModelNameLength, 'a')).ok());
}

TEST(ModelConfigTest, ParsesTextFormat) {
  auto config = ParseModelConfig(
      "exact_near_pairs: true\nkeep_versions: 2\nlimits { max_pairs_per_message: 10 }\n", "c");
  ASSERT_TRUE(config.ok()) << config.status();
  EXPECT_TRUE(config->exact_near_pairs());
  EXPECT_EQ(config->keep_versions(), 2);
  EXPECT_EQ(config->limits().max_pairs_per_message(), 10);
}

TEST(ModelConfigTest, ReportsFileLineAndColumn) {
  auto config = ParseModelConfig("keep_versions: 1\nno_such_field: 3\n", "m/config.textproto");
  ASSERT_FALSE(config.ok());
  EXPECT_EQ(config.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(config.status().message()), HasSubstr("m/config.textproto:2:"));
  EXPECT_THAT(std::string(config.status().message()), HasSubstr("no_such_field"));
}

TEST(ModelConfigTest, RejectsNegativeLimits) {
  auto config = ParseModelConfig("limits { max_matrix_cells: -1 }", "c");
  ASSERT_FALSE(config.ok());
  EXPECT_THAT(std::string(config.status().message()), HasSubstr("limits.max_matrix_cells"));
}

TEST(ModelConfigTest, MissingFileIsTheDefault) {
  testing::TempDir dir;
  auto config = LoadModelConfig(dir.path() + "/none.textproto");
  ASSERT_TRUE(config.ok()) << config.status();
  EXPECT_FALSE(config->exact_near_pairs());
}

TEST(LimitsTest, ModelLimitsOnlyLower) {
  ServiceLimits server;
  server.max_pairs_per_message = 100;
  server.max_matrix_cells = 1000;
  ModelLimits model;
  model.set_max_pairs_per_message(10);
  model.set_max_matrix_cells(5000);
  const ServiceLimits l = WithModelLimits(server, model);
  EXPECT_EQ(l.max_pairs_per_message, 10);
  EXPECT_EQ(l.max_matrix_cells, 1000);
  EXPECT_EQ(l.max_field_sources, server.max_field_sources);
}

}  // namespace
}  // namespace geodex::server
