#include "server/service/auth.h"

#include <cstdlib>
#include <fstream>

#include "gtest/gtest.h"
#include "server/model_repository_testing.h"

namespace geodex::server {
namespace {

TEST(TokenAuthTest, AcceptsOnlyConfiguredBearerTokens) {
  TokenAuth auth({"s3cret", "next"});
  EXPECT_TRUE(auth.CheckHeader("Bearer s3cret").ok());
  EXPECT_TRUE(auth.CheckHeader("bearer next").ok());
  for (const char* bad :
       {"Bearer wrong", "Bearer s3cret ", "Basic s3cret", "s3cret", "Bearer ", "Bearer s3cre"}) {
    EXPECT_EQ(auth.CheckHeader(bad).code(), absl::StatusCode::kUnauthenticated) << bad;
  }
  EXPECT_EQ(auth.CheckHeader(std::nullopt).code(), absl::StatusCode::kUnauthenticated);
  // The message never echoes what was presented.
  EXPECT_EQ(std::string(auth.CheckHeader("Bearer wrong").message()).find("wrong"),
            std::string::npos);
}

TEST(TokenAuthTest, ReadsTokenFilesSkippingCommentsAndBlanks) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/tokens";
  std::ofstream(path) << "# rotation\n\n  first  \nsecond\n";
  auto auth = TokenAuth::FromFile(path);
  ASSERT_TRUE(auth.ok()) << auth.status();
  EXPECT_TRUE(auth->CheckHeader("Bearer first").ok());
  EXPECT_TRUE(auth->CheckHeader("Bearer second").ok());
  EXPECT_FALSE(auth->CheckHeader("Bearer # rotation").ok());
}

TEST(TokenAuthTest, EmptyOrMissingSourcesAreErrors) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/empty";
  std::ofstream(path) << "# nothing\n";
  EXPECT_EQ(TokenAuth::FromFile(path).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(TokenAuth::FromFile(dir.path() + "/missing").status().code(),
            absl::StatusCode::kNotFound);
  unsetenv("GEODEX_TEST_TOKEN_UNSET");
  EXPECT_EQ(TokenAuth::FromEnv("GEODEX_TEST_TOKEN_UNSET").status().code(),
            absl::StatusCode::kNotFound);
  setenv("GEODEX_TEST_TOKEN", "tok", 1);
  auto auth = TokenAuth::FromEnv("GEODEX_TEST_TOKEN");
  ASSERT_TRUE(auth.ok());
  EXPECT_TRUE(auth->CheckHeader("Bearer tok").ok());
}

}  // namespace
}  // namespace geodex::server
