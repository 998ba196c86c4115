#pragma once

// The length of a surface path between near points (closer than a few
// geodesic-triangle edges), which is how the default mode refines them
// (§6.5): first the corridor of the chord, walked face to face from either
// end, unfolded into the plane and straightened by the funnel algorithm,
// moved off the vertices it bends round short of a straight angle on their
// other side; the gradient trace (gradient_path.h) only when both walks
// fail, bend at several saddles, or are longer than is plausible. Every
// candidate is a surface path, never shorter than the geodesic, so the
// shortest is kept.
//
// Thread safety: pure functions of immutable data and the caller's scratch.

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "core/query/engine/mesh_view.h"
#include "core/query/engine/internal/paths/gradient_path.h"
#include "core/query/engine/internal/paths/strip_funnel.h"
#include "core/query/engine/internal/paths/walk_scratch.h"
#include "core/query/engine/query_scratch.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

// A near pair's path length; `wraps` when the path bends round a mesh
// vertex (else it is a straight line through the faces it crosses: a local
// geodesic, practically always the shortest path between near points; so
// is one bending at a single saddle vertex by no more than its angle
// excess).
struct NearPath {
  double length;
  bool wraps;
};

// What the chord's walks found between near points.
struct NearWalk {
  // The shortest path the walks vouch for: a local geodesic in a corridor
  // (straight, or bending round one saddle by no more than its angle
  // excess), or a shorter doubted one beside it.
  std::optional<NearPath> path;
  // Without such a path: the shortest candidate the walks doubted (bending
  // at several saddles, or straight but longer than `plausible`), if any.
  std::optional<double> doubted;
  // The faces of the corridor of `path` (else of `doubted`), in order from
  // `from`: where the shortest path is most likely to run, the region an
  // exact check starts from. Lives in the scratch until its next walk;
  // empty when WalkNearPair was given no scratch.
  std::span<const int32_t> corridor;
};

struct NearWalkOptions {
  // A walk longer than this is doubted (it may run in a wrong corridor).
  double plausible = std::numeric_limits<double>::infinity();
  // The same for a shot and the settling of its corridor (at most
  // `plausible`): where the secant wanders, a shot may go round the wrong
  // side of a feature, so the caller may hold shots closer.
  double plausible_shot = std::numeric_limits<double>::infinity();
  // The direction in which the geodesic is expected to leave `from` (in the
  // plane of its face: GradientPaths::Heading), where the first shot is
  // aimed; zero: along the chord.
  mesh::Vec3 heading = mesh::Vec3::Zero();
  // Shoot geodesics before the chord's walks (the refinement does beyond
  // the index's own threshold, where the chord leaves the surface). Off,
  // the walks answer alone, as they do for near pairs, whose corridors are
  // short enough for the chord's pursuit.
  bool shoot = false;
};

// Geodesics shot from `from` at `to`, then the chord's walks from either
// end, between valid canonical points `from` and `to` (from the smaller
// point, for symmetry). `scratch` (optional: without, the call makes its
// own) holds the walks' memory and counts them in its NearPairStats.
NearWalk WalkNearPair(const MeshView& view, const SurfacePoint& from, const SurfacePoint& to,
                      const NearWalkOptions& options = {}, QueryScratch* scratch = nullptr);

// The shortest path found between valid canonical points `from` and `to`
// (from the smaller point, for symmetry): the walks' (WalkNearPair), else
// the gradient trace, else the shortest doubted walk; nullopt when neither a
// walk nor a trace reaches. `walk_chord`: try the chord's corridors first
// (off: the trace only, for benchmarks).
std::optional<NearPath> NearPathLength(const MeshView& view, const GradientPaths& paths,
                                       const SurfacePoint& from, const SurfacePoint& to,
                                       bool walk_chord,
                                       double plausible = std::numeric_limits<double>::infinity());

}  // namespace geodex::query
