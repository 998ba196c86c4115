#pragma once

// Test-only: the parts of a query engine (lifting, unfolding, paths, exact
// refinement) made directly over the index of a generated mesh, so that each
// part's tests exercise it without the facade.

#include <memory>
#include <stdexcept>

#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/internal/paths/gradient_path.h"
#include "core/query/engine/internal/o1/lifted_unfolding.h"
#include "core/query/engine/internal/o1/lifting.h"
#include "core/query/engine/internal/exact/local_exact.h"
#include "core/query/engine/mesh_view.h"
#include "core/build/build_testing.h"

namespace geodex::query::testing {

struct QueryParts {
  // `matrix`: kFull where a test checks the method to float precision (the
  // builder's default 24-bit codes round 2.4e-7 of a distance).
  explicit QueryParts(const mesh::Mesh& mesh, int32_t samples,
                      index::MatrixLayout matrix = index::MatrixLayout::kCoded)
      : index(Open(mesh, samples, matrix)),
        view{index->positions(), index->faces(), index->twins()},
        unfolding(*index, /*vector_lanes=*/true),
        lifting(view, index->vertices(), unfolding),
        paths(view, lifting, unfolding, /*straighten=*/true),
        exact(*index, view) {}
  QueryParts(const QueryParts&) = delete;

  static std::shared_ptr<const index::Index> Open(const mesh::Mesh& mesh, int32_t samples,
                                                  index::MatrixLayout matrix) {
    absl::StatusOr<std::string> bytes =
        geodex::testing::BuildTestIndex(mesh, samples, /*calibrate=*/false, matrix);
    if (!bytes.ok()) throw std::runtime_error(bytes.status().ToString());
    absl::StatusOr<std::shared_ptr<const index::Index>> ix = index::Index::FromBytes(*bytes);
    if (!ix.ok()) throw std::runtime_error(ix.status().ToString());
    return *ix;
  }

  std::shared_ptr<const index::Index> index;
  MeshView view;
  LiftedUnfolding unfolding;
  Lifting lifting;
  GradientPaths paths;
  LocalExact exact;
};

}  // namespace geodex::query::testing
