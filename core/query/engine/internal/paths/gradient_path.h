#pragma once

// Geodesic paths by tracing the gradient of the approximate distance field
// (Xin, Ying & He 2012, §6.2): from the target, down the O(1) field of the
// source (lifting.h, unfolding.h) face by face to the source, then
// straightened within the faces it crosses (path_straightening.h). Where the
// trace settles in a corridor round the wrong side of a feature, the trace of
// the other point's field and restarts from the vertices round either end
// find a shorter one. O(k) per trace in the faces it crosses.
//
// Thread safety: immutable; every method is const and thread-safe.

#include <vector>

#include "absl/status/statusor.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/internal/o1/lifted_unfolding.h"
#include "core/query/engine/internal/o1/lifting.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

class GradientPaths {
 public:
  // Over the engine's mesh and O(1) parts, which must outlive this object.
  // `straighten`: straighten traces (off: the raw traces of §6.2).
  GradientPaths(const MeshView& view, const Lifting& lifting, const LiftedUnfolding& unfolding,
                bool straighten)
      : view_(view), lifting_(lifting), unfolding_(unfolding), straighten_(straighten) {}

  // How far Shortest looks beyond the first straightened trace.
  enum class Search {
    // Path: the trace of the other point's field too, then restarts while
    // the path is still long.
    kFull,
    // Near pairs: the trace of the other point's field only when the first
    // wraps round a vertex; no restarts.
    kNearPair,
  };

  // The straightened trace of `from`'s field back from `to` (valid points),
  // or a shorter one found as `search` says. The first point is `from`, the
  // last `to`; consecutive points share a face. Errors: NotFound between
  // components.
  absl::StatusOr<std::vector<PathPoint>> Shortest(const SurfacePoint& from, const SurfacePoint& to,
                                                  Search search) const;

  // The direction, in the plane of from's face, in which the geodesic from
  // `from` to `to` (valid canonical points) leaves `from` as the O(1) field
  // of `to` sees it: towards `to` unfolded into that plane from the field's
  // values at the face's corners (three O(1) answers), or down the field's
  // linear gradient where they fit no point. Not normalised; zero where the
  // field is flat.
  mesh::Vec3 Heading(const SurfacePoint& from, const SurfacePoint& to) const;

  // The raw gradient trace from `from` to `to` (valid points), before
  // straightening. Errors: NotFound between components.
  absl::StatusOr<std::vector<PathPoint>> Trace(const SurfacePoint& from,
                                               const SurfacePoint& to) const;

 private:
  // Restart chains for a valid point p: for each vertex one ring out from
  // p's face, that vertex, a vertex of p's face sharing a face with it, then
  // p; consecutive points share a face.
  std::vector<std::vector<PathPoint>> RingChains(const SurfacePoint& p) const;

  MeshView view_;
  const Lifting& lifting_;
  const LiftedUnfolding& unfolding_;
  bool straighten_;
};

}  // namespace geodex::query
