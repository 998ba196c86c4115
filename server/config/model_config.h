#pragma once

// Model names and per-model configuration files of the model repository
// (server/registry/model_registry.h): DIR/<model>/config.textproto holds a
// geodex.server.ModelConfig (server/config/model_config.proto) in text format.
//
// Thread safety: pure functions.

#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "server/config/model_config.pb.h"

namespace geodex::server {

inline constexpr char kModelConfigFile[] = "config.textproto";
inline constexpr size_t kMaxModelNameLength = 128;

// OK if `name` can name a model: 1 to 128 characters from [A-Za-z0-9_.-], not
// starting with '.', no "..". Such a name is a single path component that
// cannot leave the repository directory. Errors: InvalidArgument saying why.
absl::Status ValidateModelName(std::string_view name);

// Parses a config in protobuf text format. `filename` only labels errors.
// Errors: InvalidArgument "FILE:LINE:COL: what" for syntax errors and unknown
// fields; InvalidArgument for negative limits or keep_versions.
absl::StatusOr<ModelConfig> ParseModelConfig(std::string_view text, std::string_view filename);

// Reads and parses `path`. A missing file is the default config. Errors: as
// ParseModelConfig; Internal / PermissionDenied if it cannot be read.
absl::StatusOr<ModelConfig> LoadModelConfig(const std::string& path);

}  // namespace geodex::server
