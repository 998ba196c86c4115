#include "core/common/file_util.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class FileUtilTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "geodex_file_util_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(dir_, ec);
  }
  std::vector<std::string> Files() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path dir_;
};

// Runs `write` as an unprivileged user when the test runs as root (root
// writes into read-only directories anyway): in a child that gives up root,
// with the status code and message sent back through a pipe. Returns
// nullopt when privileges cannot be dropped.
std::optional<absl::Status> WithoutRoot(const std::function<absl::Status()>& write) {
  if (geteuid() != 0) return write();
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) return std::nullopt;
  const pid_t pid = fork();
  if (pid == 0) {
    close(pipe_fds[0]);
    constexpr uid_t kNobody = 65534;
    if (setgid(kNobody) != 0 || setuid(kNobody) != 0) _exit(100);
    const absl::Status status = write();
    const std::string message(status.message());
    (void)!::write(pipe_fds[1], message.data(), message.size());
    _exit(static_cast<int>(status.code()));
  }
  close(pipe_fds[1]);
  std::string message;
  char buffer[256];
  ssize_t n;
  while ((n = read(pipe_fds[0], buffer, sizeof(buffer))) > 0) message.append(buffer, n);
  close(pipe_fds[0]);
  int wait_status = 0;
  if (waitpid(pid, &wait_status, 0) != pid || !WIFEXITED(wait_status) ||
      WEXITSTATUS(wait_status) == 100) {
    return std::nullopt;
  }
  return absl::Status(static_cast<absl::StatusCode>(WEXITSTATUS(wait_status)), message);
}

TEST_F(FileUtilTest, WriteThenReadGivesTheSameBytes) {
  const std::string path = (dir_ / "data.bin").string();
  const std::string bytes("a\0b\nc\xff", 6);
  ASSERT_TRUE(AtomicWriteFile(path, bytes).ok());
  absl::StatusOr<std::string> read = ReadWholeFile(path);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(*read, bytes);
  // Replacing leaves only the file itself: no temporary file behind.
  ASSERT_TRUE(AtomicWriteFile(path, "").ok());
  EXPECT_EQ(*ReadWholeFile(path), "");
  EXPECT_EQ(Files(), std::vector<std::string>{"data.bin"});
}

TEST_F(FileUtilTest, ReadersNeverSeeAPartialFile) {
  const std::string path = (dir_ / "data.bin").string();
  constexpr size_t kSize = 1 << 20;
  const std::string a(kSize, 'a'), b(kSize, 'b');
  ASSERT_TRUE(AtomicWriteFile(path, a).ok());
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (int round = 0; round < 12; ++round) {
      EXPECT_TRUE(AtomicWriteFile(path, round % 2 == 0 ? b : a).ok());
    }
    done = true;
  });
  int reads = 0, bad = 0;
  while (!done || reads == 0) {
    const absl::StatusOr<std::string> read = ReadWholeFile(path);
    ++reads;
    // A non-atomic writer shows a missing, short or mixed file here.
    if (!read.ok() || (*read != a && *read != b)) ++bad;
  }
  writer.join();
  EXPECT_EQ(bad, 0) << "of " << reads << " reads";
  EXPECT_EQ(Files(), std::vector<std::string>{"data.bin"});
}

TEST_F(FileUtilTest, ReadOnlyDirectoryIsPermissionDeniedAndKeepsTheOldFile) {
  const fs::path locked = dir_ / "locked";
  fs::create_directory(locked);
  const std::string path = (locked / "data.bin").string();
  ASSERT_TRUE(AtomicWriteFile(path, "old").ok());
  // Traversable by anyone (the unprivileged child too), writable by no one.
  fs::permissions(dir_, fs::perms::owner_all | fs::perms::group_exec | fs::perms::others_exec);
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_exec |
                              fs::perms::others_read | fs::perms::others_exec);
  const std::optional<absl::Status> status =
      WithoutRoot([&] { return AtomicWriteFile(path, "new"); });
  if (!status.has_value()) GTEST_SKIP() << "cannot drop root privileges";
  EXPECT_EQ(status->code(), absl::StatusCode::kPermissionDenied) << *status;
  EXPECT_THAT(status->message(), HasSubstr(path));
  EXPECT_THAT(status->message(), HasSubstr("Permission denied"));
  EXPECT_EQ(*ReadWholeFile(path), "old");
  EXPECT_EQ(std::distance(fs::directory_iterator(locked), fs::directory_iterator()), 1);
}

// What a writer killed before its rename leaves is removed by the next write
// of the same path; a live writer's temporary and other files are kept.
TEST_F(FileUtilTest, NextWriteRemovesTheTemporariesOfDeadWriters) {
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  ASSERT_GT(dead, 0);
  ASSERT_EQ(waitpid(dead, nullptr, 0), dead);
  auto touch = [&](const std::string& name) {
    ASSERT_TRUE(AtomicWriteFile((dir_ / name).string(), "x").ok());
  };
  const std::string abandoned = "data.bin.tmp." + std::to_string(dead) + ".0123456789abcdef";
  const std::string live = "data.bin.tmp." + std::to_string(getpid()) + ".fedcba9876543210";
  touch(abandoned);
  touch(live);
  touch("other.bin.tmp." + std::to_string(dead) + ".0123456789abcdef");  // another path's
  touch("data.bin.tmp.notapid.0123456789abcdef");                       // not a temporary
  touch("data.bin");

  ASSERT_TRUE(AtomicWriteFile((dir_ / "data.bin").string(), "new").ok());
  const std::vector<std::string> files = Files();
  EXPECT_THAT(files, ::testing::Not(::testing::Contains(abandoned)));
  EXPECT_THAT(files, ::testing::Contains(live));
  EXPECT_EQ(files.size(), 4u) << ::testing::PrintToString(files);
  EXPECT_EQ(*ReadWholeFile((dir_ / "data.bin").string()), "new");
}

TEST(ErrnoErrorTest, AFullDiskIsResourceExhaustedAndSaysSo) {
  for (int err : {ENOSPC, EDQUOT, EFBIG}) {
    const absl::Status status = ErrnoError(err, "cannot write", "/x/y.gdx");
    EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted) << status;
    EXPECT_THAT(status.message(), HasSubstr("/x/y.gdx"));
  }
  EXPECT_THAT(ErrnoError(ENOSPC, "cannot write", "f").message(),
              HasSubstr("No space left on device"));
}

TEST_F(FileUtilTest, MissingDirectoryIsNotFound) {
  const std::string path = (dir_ / "no" / "such" / "data.bin").string();
  const absl::Status status = AtomicWriteFile(path, "x");
  EXPECT_EQ(status.code(), absl::StatusCode::kNotFound) << status;
  EXPECT_THAT(status.message(), HasSubstr(path));
}

TEST_F(FileUtilTest, ReadErrorsSayWhatIsWrong) {
  const std::string missing = (dir_ / "missing.txt").string();
  absl::StatusOr<std::string> read = ReadWholeFile(missing);
  EXPECT_EQ(read.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(read.status().message(), HasSubstr(missing));
  EXPECT_THAT(read.status().message(), HasSubstr("No such file"));
  // A directory is no file to read.
  read = ReadWholeFile(dir_.string());
  EXPECT_EQ(read.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(read.status().message(), HasSubstr("directory"));

  const std::string secret = (dir_ / "secret.txt").string();
  ASSERT_TRUE(AtomicWriteFile(secret, "x").ok());
  fs::permissions(secret, fs::perms::owner_write);
  fs::permissions(dir_, fs::perms::owner_all | fs::perms::group_exec | fs::perms::others_exec);
  const std::optional<absl::Status> status =
      WithoutRoot([&] { return ReadWholeFile(secret).status(); });
  if (!status.has_value()) GTEST_SKIP() << "cannot drop root privileges";
  EXPECT_EQ(status->code(), absl::StatusCode::kPermissionDenied) << *status;
  EXPECT_THAT(status->message(), HasSubstr(secret));
}

}  // namespace
}  // namespace geodex
