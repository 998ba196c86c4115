#pragma once

// Exact answers near a point, for what the O(1) answer cannot settle: the
// near-pair mode kExact and a caller's tolerance (§6.5), the exact distances
// round a point, and the exact path within a corridor round a traced one.
// They run the window engine (core/geodesic/exact_geodesic.h) on the index's
// mesh, rebuilt from the mapped arrays on first use; their cost grows with
// the faces they reach, not O(1).
//
// Thread safety: every const method is thread-safe; the lazily made mesh is
// built once under a std::once_flag. A solver's working memory is the
// caller's QueryScratch, one per thread.

#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geodesic/confined_geodesic.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/index/coarse_surface.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/internal/exact/exact_scratch.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/query_scratch.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

class LocalExact {
 public:
  // Over `index` and its mesh `view`, which must outlive this object.
  LocalExact(const index::Index& index, const MeshView& view);
  ~LocalExact();

  // The exact distance between valid canonical points, by one propagation
  // from `from` that stops when it reaches `to`; nullopt when the index's
  // mesh cannot be rebuilt or the propagation fails. `scratch` (optional)
  // keeps the solver between calls.
  std::optional<double> NearDistance(const SurfacePoint& from, const SurfacePoint& to,
                                     QueryScratch* scratch) const;

  // The exact distance between valid canonical points, by a propagation
  // confined to a region of faces round them that grows until it certifies
  // its answer (core/geodesic/confined_geodesic.h): its cost follows the
  // region, not the mesh. `seed_faces`: the faces the region starts
  // from (e.g. a path's; empty: a shortest chain of faces between the
  // points'). `upper_bound`: the length of a surface path between them, if
  // one is known (it focuses the propagation). nullopt as NearDistance. `scratch` keeps the solver
  // between calls.
  std::optional<double> ConfinedDistance(const SurfacePoint& from, const SurfacePoint& to,
                                         std::span<const int32_t> seed_faces, QueryScratch& scratch,
                                         double upper_bound = kInf) const;

  // Exact distances from a valid canonical point to every vertex within
  // `radius` (larger values or +inf beyond). The span lives in `scratch`
  // until its next use. Errors: InvalidArgument for a negative radius;
  // Internal when the index's mesh cannot be rebuilt.
  absl::StatusOr<std::span<const double>> Distances(const SurfacePoint& p, double radius,
                                                    QueryScratch& scratch) const;

  // Exact distances from the nearest of valid canonical `sources` to every
  // vertex within `radius`, by one propagation from all of them: the vertices
  // ascending, each with its distance and the index (into `sources`) of its
  // nearest source. The cost follows the faces reached, not the mesh: the
  // solver resets only what its last propagation touched, and the vertices
  // are read from the list of those it reached. Errors: InvalidArgument for a
  // radius that is not finite and > 0 or no source; ResourceExhausted when
  // `max_vertices` > 0 and the propagation reaches more vertices (it stops
  // there); Internal when the index's mesh cannot be rebuilt or the
  // propagation exceeds the solver's window budget (GeodesicOptions::
  // max_windows, a safety net against pathological meshes).
  absl::StatusOr<RadiusField> DistancesWithin(std::span<const SurfacePoint> sources, double radius,
                                              int64_t max_vertices, QueryScratch& scratch) const;

  // The exact shortest path from the first point of `path` to its last
  // among the faces within `steps` edge steps of the faces `path` crosses,
  // or an error (e.g. when that corridor is not a manifold mesh).
  absl::StatusOr<std::vector<PathPoint>> CorridorPath(const std::vector<PathPoint>& path,
                                                      int32_t steps) const;

 private:
  // The mesh for exact propagations, made on first use; null when it cannot
  // be made.
  const mesh::Mesh* ExactMesh() const;
  // The surface before the long-edge split, made on first use (without
  // ExactMesh(): fields alone need that); null when nothing was split or it
  // cannot be made. The split is flat: a pair's distance is the same there,
  // over up to several times fewer faces.
  const mesh::Mesh* CoarseMesh() const;
  // The scratch's solvers over ExactMesh(), made on first use; null when
  // the mesh cannot be made.
  ExactSolvers* Solvers(QueryScratch& scratch) const;
  // The same over the coarse surface when there is one, else over
  // ExactMesh(); `coarse` says which.
  ExactSolvers* PairSolvers(QueryScratch& scratch, bool* coarse) const;
  // A point of the index's mesh as the same point of the coarse surface.
  SurfacePoint ToCoarse(const SurfacePoint& p) const;

  const index::Index* index_;
  MeshView view_;
  mutable std::once_flag mesh_once_, coarse_once_;
  mutable std::unique_ptr<mesh::Mesh> mesh_;
  mutable std::unique_ptr<mesh::Mesh> coarse_;
};

}  // namespace geodex::query
