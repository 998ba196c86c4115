#include "server/config/model_config.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "google/protobuf/io/tokenizer.h"
#include "google/protobuf/text_format.h"

namespace geodex::server {
namespace {

// Collects the first parser error as "FILE:LINE:COL: message" (1-based).
class FirstErrorCollector : public google::protobuf::io::ErrorCollector {
 public:
  explicit FirstErrorCollector(std::string filename) : filename_(std::move(filename)) {}
  void AddError(int line, google::protobuf::io::ColumnNumber column,
                const std::string& message) override {
    if (error_.empty())
      error_ = absl::StrFormat("%s:%d:%d: %s", filename_, line + 1, column + 1, message);
  }
  const std::string& error() const { return error_; }

 private:
  std::string filename_;
  std::string error_;
};

bool IsNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '.' || c == '-';
}

}  // namespace

absl::Status ValidateModelName(std::string_view name) {
  if (name.empty()) return absl::InvalidArgumentError("model name is empty");
  if (name.size() > kMaxModelNameLength) {
    return absl::InvalidArgumentError(absl::StrFormat("model name has %d characters, more than %d",
                                                      name.size(), kMaxModelNameLength));
  }
  for (size_t i = 0; i < name.size(); ++i) {
    if (!IsNameChar(name[i])) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "model name '%s': character %d (0x%02x) is not one of [A-Za-z0-9_.-]",
          absl::CHexEscape(std::string(name)), i, static_cast<unsigned char>(name[i])));
    }
  }
  if (name[0] == '.') {
    return absl::InvalidArgumentError(
        absl::StrFormat("model name '%s' starts with '.'", std::string(name)));
  }
  if (name.find("..") != std::string_view::npos) {
    return absl::InvalidArgumentError(
        absl::StrFormat("model name '%s' contains '..'", std::string(name)));
  }
  return absl::OkStatus();
}

absl::StatusOr<ModelConfig> ParseModelConfig(std::string_view text, std::string_view filename) {
  ModelConfig config;
  google::protobuf::TextFormat::Parser parser;
  FirstErrorCollector errors{std::string(filename)};
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(std::string(text), &config)) {
    return absl::InvalidArgumentError(errors.error().empty()
                                          ? absl::StrCat(std::string(filename), ": does not parse")
                                          : errors.error());
  }
  const ModelLimits& l = config.limits();
  const std::pair<const char*, int64_t> checks[] = {
      {"keep_versions", config.keep_versions()},
      {"limits.max_pairs_per_message", l.max_pairs_per_message()},
      {"limits.max_matrix_cells", l.max_matrix_cells()},
      {"limits.max_field_sources", l.max_field_sources()},
      {"limits.max_path_pairs", l.max_path_pairs()},
      {"limits.max_locate_positions", l.max_locate_positions()},
      {"limits.max_field_vertices", l.max_field_vertices()},
  };
  for (const auto& [field, value] : checks) {
    if (value < 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: %s is negative (%d)", std::string(filename), field, value));
    }
  }
  return config;
}

absl::StatusOr<ModelConfig> LoadModelConfig(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (errno == ENOENT) return ModelConfig();
    const int err = errno;
    const std::string message = absl::StrFormat("%s: %s", path, std::strerror(err));
    if (err == EACCES) return absl::PermissionDeniedError(message);
    return absl::InternalError(message);
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return absl::InternalError(absl::StrFormat("%s: read failed", path));
  return ParseModelConfig(text.str(), path);
}

}  // namespace geodex::server
