#pragma once

// Test utilities: an index of a generated mesh, built the way every test
// wants it (seed 1, two threads, its accuracy calibration on request), and a
// query engine over it. Test-only (library geodex_build_testing).

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "core/index/sample_matrix.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_repair.h"
#include "core/query/engine/query_engine.h"

namespace geodex::testing {

// The index file bytes of `mesh` with `samples` samples, calibrated when
// `calibrate`, its sample matrix stored as `matrix` (the builder's 24-bit
// codes by default; kFull where a test measures the method to float
// precision). Errors: the builder's and the calibration's.
absl::StatusOr<std::string> BuildTestIndex(
    const mesh::Mesh& mesh, int32_t samples, bool calibrate = false,
    index::MatrixLayout matrix = index::MatrixLayout::kCoded);

// A query engine over BuildTestIndex's index.
absl::StatusOr<std::shared_ptr<const query::QueryEngine>> BuildTestEngine(
    const mesh::Mesh& mesh, int32_t samples, bool calibrate = false,
    query::QueryOptions options = {}, index::MatrixLayout matrix = index::MatrixLayout::kCoded);

// The same, for test bodies: throws std::runtime_error with the status on
// failure, which GoogleTest reports as the test's failure (no dereference of
// an error).
std::shared_ptr<const query::QueryEngine> TestEngineOrThrow(
    const mesh::Mesh& mesh, int32_t samples, bool calibrate = false,
    query::QueryOptions options = {}, index::MatrixLayout matrix = index::MatrixLayout::kCoded);

// A mesh file's triangles repaired, split (the long-edge split, when
// `split`) and built as geodex-build does, and a query engine over the
// index: for tests of answers in the input's ids. Throws std::runtime_error
// with the status on failure.
struct RepairedTestEngine {
  mesh::RepairedMesh repaired;
  std::shared_ptr<const query::QueryEngine> engine;
};
RepairedTestEngine RepairedTestEngineOrThrow(const mesh::RawMesh& raw, int32_t samples,
                                             bool split = false);

}  // namespace geodex::testing
