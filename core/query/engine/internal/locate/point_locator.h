#pragma once

// Point location: the closest surface point to a 3D position, through an
// axis-aligned bounding-box hierarchy over the faces (built by
// index::BuildFaceBvh, core/index/face_bvh.h, and stored in the index so the
// server uses it in place).
//
// Thread safety: PointLocator is a read-only view; Locate is const and safe
// from any number of threads.

#include <cstdint>
#include <span>

#include "Eigen/Core"
#include "absl/status/statusor.h"
#include "core/index/index_format.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

class PointLocator {
 public:
  // Views; the spans must outlive the locator.
  PointLocator(std::span<const double> positions, std::span<const int32_t> faces,
               std::span<const index::BvhNode> nodes, std::span<const int32_t> leaf_faces);

  // The closest point of the surface to `x`. Ties go to the lowest face id.
  // Errors: InvalidArgument for a non-finite `x`; FailedPrecondition for an
  // empty hierarchy.
  absl::StatusOr<LocatedPoint> Locate(const Eigen::Vector3d& x) const;

 private:
  std::span<const double> positions_;
  std::span<const int32_t> faces_;
  std::span<const index::BvhNode> nodes_;
  std::span<const int32_t> leaf_faces_;
};

}  // namespace geodex::query
