#include "core/common/file_util.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <random>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex {

absl::Status ErrnoError(int err, const std::string& what, const std::string& path) {
  const std::string message = absl::StrFormat("%s %s: %s", what, path, std::strerror(err));
  switch (err) {
    case ENOENT:
    case ENOTDIR:
      return absl::NotFoundError(message);
    case EACCES:
    case EPERM:
    case EROFS:
      return absl::PermissionDeniedError(message);
    case ENOSPC:
    case EDQUOT:
    case EFBIG:
      return absl::ResourceExhaustedError(message);
    default:
      return absl::InternalError(message);
  }
}

namespace {

// "<name>.tmp.<pid>.<16 hex digits>": AtomicWriteFile's temporary for `name`;
// the pid of its writer, or 0 when `entry` is not one.
pid_t TemporaryWriter(const std::string& entry, const std::string& name) {
  const std::string prefix = name + ".tmp.";
  if (entry.size() <= prefix.size() || entry.compare(0, prefix.size(), prefix) != 0) return 0;
  const std::string rest = entry.substr(prefix.size());
  const size_t dot = rest.find('.');
  if (dot == std::string::npos || dot == 0 || dot > 9 || rest.size() - dot - 1 != 16) return 0;
  pid_t pid = 0;
  for (size_t i = 0; i < dot; ++i) {
    if (rest[i] < '0' || rest[i] > '9') return 0;
    pid = pid * 10 + (rest[i] - '0');
  }
  for (size_t i = dot + 1; i < rest.size(); ++i) {
    if (!std::isxdigit(static_cast<unsigned char>(rest[i]))) return 0;
  }
  return pid;
}

// Removes the temporaries of `name` in `dir` whose writer is no longer
// running on this host: what a writer killed before its rename leaves. A
// live writer's temporary is kept (kill(pid, 0) succeeds or says EPERM).
void RemoveAbandonedTemporaries(const std::string& dir, const std::string& name) {
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return;  // the create below reports why
  std::vector<std::string> abandoned;
  while (const struct dirent* e = ::readdir(d)) {
    const pid_t pid = TemporaryWriter(e->d_name, name);
    if (pid != 0 && ::kill(pid, 0) != 0 && errno == ESRCH) abandoned.emplace_back(e->d_name);
  }
  ::closedir(d);
  for (const std::string& entry : abandoned) ::unlink((dir + "/" + entry).c_str());
}

}  // namespace

absl::Status AtomicWriteFile(const std::string& path, std::string_view bytes) {
  const size_t slash = path.rfind('/');
  const std::string dir =
      slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  RemoveAbandonedTemporaries(dir, slash == std::string::npos ? path : path.substr(slash + 1));
  std::random_device random;
  const uint64_t nonce = (uint64_t{random()} << 32) ^ random();
  const std::string tmp = absl::StrFormat("%s.tmp.%d.%016x", path, ::getpid(), nonce);

  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return ErrnoError(errno, "cannot create temporary file", tmp);
  // On any failure before the rename: close and remove the temporary file.
  auto abandon = [&](int err, const std::string& what) {
    if (fd >= 0) ::close(fd);
    ::unlink(tmp.c_str());
    return ErrnoError(err, what, tmp);
  };
  size_t written = 0;
  while (written < bytes.size()) {
    const size_t chunk = std::min<size_t>(bytes.size() - written, size_t{1} << 30);
    const ssize_t n = ::write(fd, bytes.data() + written, chunk);
    if (n < 0) {
      if (errno == EINTR) continue;
      return abandon(errno, "cannot write");
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) return abandon(errno, "cannot fsync");
  const int close_result = ::close(fd);
  fd = -1;
  if (close_result != 0) return abandon(errno, "cannot close");
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    return ErrnoError(err, absl::StrFormat("cannot rename %s to", tmp), path);
  }
  // The rename is durable only once the directory entry is. A failure here
  // leaves the new file in place (complete) but reports the error.
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd < 0) return ErrnoError(errno, "cannot open the directory of", path);
  const int sync_result = ::fsync(dir_fd);
  const int sync_errno = errno;
  ::close(dir_fd);
  if (sync_result != 0) return ErrnoError(sync_errno, "cannot fsync the directory of", path);
  return absl::OkStatus();
}

absl::StatusOr<int> OpenForReading(const std::string& path, struct stat* info) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return ErrnoError(errno, "cannot open", path);
  if (::fstat(fd, info) != 0) {
    const int err = errno;
    ::close(fd);
    return ErrnoError(err, "cannot stat", path);
  }
  return fd;
}

absl::StatusOr<std::string> ReadWholeFile(const std::string& path) {
  struct stat info;
  GEODEX_ASSIGN_OR_RETURN(const int fd, OpenForReading(path, &info));
  // open() accepts a directory; there is no file to read at that path.
  if (S_ISDIR(info.st_mode)) {
    ::close(fd);
    return absl::NotFoundError(absl::StrFormat("cannot read %s: it is a directory", path));
  }
  std::string contents;
  if (S_ISREG(info.st_mode)) contents.reserve(static_cast<size_t>(info.st_size));
  char buffer[1 << 16];
  while (true) {
    const ssize_t n = ::read(fd, buffer, sizeof(buffer));
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      return ErrnoError(err, "cannot read", path);
    }
    contents.append(buffer, static_cast<size_t>(n));
  }
  ::close(fd);
  return contents;
}

absl::Status ByteReader::Truncated() const {
  return absl::DataLossError(absl::StrFormat("%s is truncated or corrupt", what_));
}

}  // namespace geodex
