#pragma once

// Files and lines for the offline tools' tests: a scratch directory of the
// test's own, a file written into it, a file read back, output split into
// lines.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_split.h"

namespace geodex::tools::testing {

// temp_directory_path()/`name`, made when missing.
inline std::filesystem::path TestDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::create_directories(dir);
  return dir;
}

// Writes `text` to `dir`/`file` and returns its path.
inline std::string WriteTestFile(const std::filesystem::path& dir, const std::string& file,
                                 const std::string& text) {
  const std::string path = (dir / file).string();
  std::ofstream(path) << text;
  return path;
}

inline std::string ReadTestFile(const std::string& path) {
  std::ostringstream text;
  text << std::ifstream(path).rdbuf();
  return text.str();
}

// The non-empty lines of `text`.
inline std::vector<std::string> Lines(const std::string& text) {
  return absl::StrSplit(text, '\n', absl::SkipEmpty());
}

}  // namespace geodex::tools::testing
