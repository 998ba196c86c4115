#include "server/server_command_line.h"

#include <filesystem>
#include <fstream>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::server {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

// A directory for --models and a file for the TLS and token flags, both
// existing as CLI11 checks.
class ServerCommandLineTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (std::filesystem::temp_directory_path() / "geodex_server_command_line_test").string();
    std::filesystem::create_directories(dir_);
    file_ = dir_ + "/file.pem";
    std::ofstream(file_) << "x\n";
  }

  // Parses `flags` (without the program name) into `cli`.
  void Parse(ServerCommandLine& cli, const std::string& flags) {
    cli.app().parse("--models " + dir_ + " --listen 0.0.0.0:8980 " + flags, false);
  }

  std::string dir_, file_;
};

TEST_F(ServerCommandLineTest, Defaults) {
  ServerCommandLine cli;
  Parse(cli, "");
  const ServerOptions options = cli.Options();
  const ServerOptions defaults;
  EXPECT_EQ(options.models_dir, dir_);
  EXPECT_EQ(options.listen, "0.0.0.0:8980");
  EXPECT_EQ(options.metrics_listen, "");
  EXPECT_EQ(options.workers, 0);
  EXPECT_EQ(options.queue_capacity, 0);
  EXPECT_EQ(options.poll_interval, absl::Seconds(10));
  EXPECT_EQ(options.limits.max_message_bytes, defaults.limits.max_message_bytes);
  EXPECT_EQ(options.limits.max_pairs_per_message, defaults.limits.max_pairs_per_message);
  EXPECT_TRUE(options.reflection);
  EXPECT_EQ(options.tls.cert_file, "");
  EXPECT_EQ(cli.drain(), absl::Seconds(20));
  EXPECT_EQ(cli.log_level(), "info");
}

TEST_F(ServerCommandLineTest, FlagsReachTheOptions) {
  ServerCommandLine cli;
  Parse(cli,
        "--metrics :9090 --workers 3 --queue 100 --poll-seconds 0.5 --drain-seconds 2 "
        "--max-pairs 10 --max-matrix-cells 20 --max-field-sources 30 --max-path-pairs 40 "
        "--max-locate 50 --max-message-mib 3 --max-streams 6 --stream-window 7 "
        "--no-reflection --log-level warn --token-env GEODEX_TOKEN");
  const ServerOptions o = cli.Options();
  EXPECT_EQ(o.metrics_listen, ":9090");
  EXPECT_EQ(o.workers, 3);
  EXPECT_EQ(o.queue_capacity, 100);
  EXPECT_EQ(o.poll_interval, absl::Milliseconds(500));
  EXPECT_EQ(cli.drain(), absl::Seconds(2));
  EXPECT_EQ(o.limits.max_pairs_per_message, 10);
  EXPECT_EQ(o.limits.max_matrix_cells, 20);
  EXPECT_EQ(o.limits.max_field_sources, 30);
  EXPECT_EQ(o.limits.max_path_pairs, 40);
  EXPECT_EQ(o.limits.max_locate_positions, 50);
  EXPECT_EQ(o.limits.max_message_bytes, int64_t{3} << 20);
  EXPECT_EQ(o.limits.max_concurrent_streams, 6);
  EXPECT_EQ(o.limits.stream_window, 7);
  EXPECT_FALSE(o.reflection);
  EXPECT_EQ(cli.log_level(), "warn");
  EXPECT_EQ(o.token_env, "GEODEX_TOKEN");
}

TEST_F(ServerCommandLineTest, TlsFiles) {
  ServerCommandLine cli;
  Parse(cli, "--tls-cert " + file_ + " --tls-key " + file_ + " --tls-ca " + file_ +
                 " --token-file " + file_);
  const ServerOptions o = cli.Options();
  EXPECT_EQ(o.tls.cert_file, file_);
  EXPECT_EQ(o.tls.key_file, file_);
  EXPECT_EQ(o.tls.ca_file, file_);
  EXPECT_EQ(o.token_file, file_);
}

TEST_F(ServerCommandLineTest, RefusesWhatCli11Checks) {
  const auto parse = [&](const std::string& flags) {
    ServerCommandLine cli;
    Parse(cli, flags);
  };
  EXPECT_THROW(parse("--tls-cert " + file_), CLI::RequiresError);
  EXPECT_THROW(parse("--tls-key " + file_), CLI::RequiresError);
  EXPECT_THROW(parse("--tls-ca " + file_), CLI::RequiresError);
  EXPECT_THROW(parse("--tls-cert " + dir_ + "/missing --tls-key " + file_), CLI::ValidationError);
  EXPECT_THROW(parse("--token-file " + file_ + " --token-env X"), CLI::ExcludesError);
  EXPECT_THROW(parse("--workers 5000"), CLI::ValidationError);
  EXPECT_THROW(parse("--max-pairs 0"), CLI::ValidationError);
  EXPECT_THROW(parse("--max-message-mib 2048"), CLI::ValidationError);
  EXPECT_THROW(parse("--stream-window 0"), CLI::ValidationError);
  EXPECT_THROW(parse("--poll-seconds -1"), CLI::ValidationError);
  EXPECT_THROW(parse("--log-level verbose"), CLI::ValidationError);

  ServerCommandLine no_listen;
  EXPECT_THROW(no_listen.app().parse("--models " + dir_, false), CLI::RequiredError);
  ServerCommandLine missing_models;
  EXPECT_THROW(missing_models.app().parse("--models " + dir_ + "/missing --listen :1", false),
               CLI::ValidationError);
}

TEST_F(ServerCommandLineTest, Help) {
  ServerCommandLine cli;
  const std::string help = cli.app().help();
  EXPECT_THAT(help, StartsWith("geodex-server: constant-time geodesic distance queries over gRPC"));
  EXPECT_THAT(help, HasSubstr("--no-reflection"));
  EXPECT_THAT(help, HasSubstr("--max-message-mib"));
}

}  // namespace
}  // namespace geodex::server
