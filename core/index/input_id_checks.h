#pragma once

// The checks of an index's input-id sections (format 1.2: input faces and
// vertex copies; 2.0: the long-edge split's coarse faces and pieces), shared
// by the writer (InvalidArgument) and the reader (DataLoss) through
// index.cc's CheckContents.

#include <cstdint>
#include <span>

#include "absl/status/status.h"
#include "core/index/index_format.h"
#include "core/index/split_view.h"

namespace geodex::index {

struct InputIdSections {
  int64_t num_vertices = 0;
  int64_t num_faces = 0;
  std::span<const InputFaceRecord> input_faces;
  std::span<const int32_t> vertex_copies;
  SplitView split;
  uint64_t split_vertices = 0;
};

// OK, or `code` with a message naming the first bad element.
absl::Status CheckInputIds(const InputIdSections& c, absl::StatusCode code);

}  // namespace geodex::index
