#pragma once

// The project's one whole-file reader and one atomic file writer, and the
// byte encoders of the builder's work files and the index.

#include <sys/stat.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace geodex {

// Writes `bytes` to `path` atomically: a temporary file in the same directory,
// fsync, rename over `path`, fsync of the directory. Readers see the old file
// or the new one, never a partial one; on failure the temporary file is
// removed and an existing `path` is left as it was. A writer killed before its
// rename leaves its temporary ("<path>.tmp.<pid>.<nonce>"); the next write of
// `path` removes those whose process no longer runs on this host. Errors
// (ErrnoError, naming the path and the reason): NotFound when the directory
// does not exist, PermissionDenied when it may not be written (read-only, no
// access), ResourceExhausted when the disk or quota is full, Internal
// otherwise. Thread-safe: concurrent writers of one path each use their own
// temporary file, and the last rename wins.
absl::Status AtomicWriteFile(const std::string& path, std::string_view bytes);

// An error for a failed system call: "<what> <path>: <strerror(err)>", as
// NotFound (ENOENT, ENOTDIR), PermissionDenied (EACCES, EPERM, EROFS),
// ResourceExhausted (ENOSPC, EDQUOT, EFBIG) or Internal.
absl::Status ErrnoError(int err, const std::string& what, const std::string& path);

// Opens `path` read-only (close-on-exec) and fills `info` (fstat); returns the
// descriptor, which the caller closes. Errors: ErrnoError's. Thread-safe.
absl::StatusOr<int> OpenForReading(const std::string& path, struct stat* info);

// Reads a whole file. Errors (naming the path and the reason): NotFound when
// there is no file at `path` (missing, a path through a non-directory, or a
// directory); PermissionDenied when it may not be read; Internal when reading
// fails. Thread-safe.
absl::StatusOr<std::string> ReadWholeFile(const std::string& path);

// Appends plain values and arrays to a byte string (host byte order, which the
// readers check through their own headers).
class ByteWriter {
 public:
  template <typename T>
  void Put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  template <typename T>
  void PutVector(const std::vector<T>& values) {
    Put<uint64_t>(values.size());
    bytes_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

// Reads what ByteWriter wrote, with bounds checks: every failure is DataLoss
// naming `what`.
class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::string what) : bytes_(bytes), what_(std::move(what)) {}

  template <typename T>
  absl::Status Get(T* value) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (bytes_.size() - pos_ < sizeof(T)) return Truncated();
    std::memcpy(value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return absl::OkStatus();
  }
  template <typename T>
  absl::Status GetVector(std::vector<T>* values) {
    uint64_t n = 0;
    if (absl::Status s = Get(&n); !s.ok()) return s;
    if (n > (bytes_.size() - pos_) / sizeof(T)) return Truncated();
    values->resize(n);
    std::memcpy(values->data(), bytes_.data() + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
    return absl::OkStatus();
  }
  bool AtEnd() const { return pos_ == bytes_.size(); }

 private:
  absl::Status Truncated() const;

  std::string_view bytes_;
  size_t pos_ = 0;
  std::string what_;
};

}  // namespace geodex
