#pragma once

// The exact geodesic distance between two nearby surface points, by window
// propagation (the ICH engine of exact_geodesic.h) confined to a region of
// faces round them, grown until its answer is provably the distance on the
// whole mesh. Its cost follows the region, not the mesh.
//
// The region R starts as the given seed faces (e.g. the faces a walk from p
// to q crossed; without seeds, a shortest chain of edge-adjacent faces from
// p's face to q's) with the faces of both points, plus their one-ring (the
// faces sharing a vertex with them). A propagation from p inside R gives
// d_R(q), the length of a shortest path from p to q inside R: the length of
// an actual path, so d(p,q) <= d_R(q).
//
// Certificate. The border of R is the set of edges with one face in R and
// the other outside (edges on the mesh boundary are not part of it: no path
// crosses them). A path from p to q that is not inside R leaves R for the
// first time at a point b of a border edge (also when it leaves through a
// vertex: that vertex ends a border edge); its part up to b lies inside R,
// so its length is at least d_R(b) + |b - q|, the second term the Euclidean
// lower bound on the rest. The propagation gives d_R exactly on every border
// edge e, as the minimum of the windows that reached e and the distances of
// e's face's corners plus straight segments, so
//   B(e) = min over those terms t of min over b on e of [t(b) + |b - q|]
// is computed in closed form (b is on a segment, the minimum of a sum of two
// distances to it is found by unfolding one point across the segment's line).
// When the propagation stopped early at q, points of e at least as far as
// the front are covered by the front itself, which is no nearer than d_R(q).
// If B(e) >= d_R(q) (up to rounding, a relative 1e-12) for every border edge,
// no path that leaves R is shorter, and d(p,q) = d_R(q). Otherwise R grows
// by the faces round the violating edges' ends (one ring, then two, four,
// ...: each round at least adds the faces beyond them) and the propagation
// runs again. A point q not reached inside R counts as a violation of every
// border edge; once R has no border (a whole component), d_R is d, which is
// +inf for points of different components.
//
// Example:
//   geodex::geodesic::ConfinedGeodesicSolver solver(mesh);
//   GEODEX_ASSIGN_OR_RETURN(double d, solver.Distance(p, q, walked_faces));
//
// Thread safety: a solver holds scratch space for its region and its
// propagation (allocated once, reset in proportion to what a call touched)
// and is not thread-safe; use one per thread. Any number of solvers may
// share one const Mesh.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/mesh.h"

namespace geodex::geodesic {

struct ConfinedOptions {
  // Vertex rings added round the seed faces (and the points' faces) before
  // the first propagation: 1 is the one-ring.
  int32_t seed_rings = 1;
};

// What the last call did.
struct ConfinedStats {
  // Propagations run: 1 when the first region was certified.
  int32_t rounds = 0;
  // Faces of the last region, and its border edges.
  int32_t region_faces = 0;
  int32_t border_edges = 0;
  // Windows created over all rounds.
  int64_t windows_created = 0;
};

class ConfinedGeodesicSolver {
 public:
  // `mesh` must outlive the solver.
  explicit ConfinedGeodesicSolver(const Mesh& mesh, const ConfinedOptions& options = {});
  // Runs its propagations on `engine` (over the mesh to confine to), which
  // must outlive the solver: a caller that also propagates over the whole
  // mesh keeps one engine's arrays, not two. The engine keeps no state
  // between propagations that the other's would see.
  explicit ConfinedGeodesicSolver(ExactGeodesicSolver& engine,
                                  const ConfinedOptions& options = {});

  // The exact geodesic distance between p and q on the whole mesh (+inf when
  // they lie in different components), computed inside a region grown from
  // `seed_faces` (may be empty; duplicates allowed). Errors: InvalidArgument
  // for a malformed point, OutOfRange for a face id past the end (a point's
  // or a seed's); ResourceExhausted from the engine's window limit.
  // `upper_bound`, if finite, must be no shorter than the distance (e.g. the
  // length of a surface path from p to q): the first region is then the
  // faces that may meet the ellipsoid it bounds (see Distance's rounds).
  absl::StatusOr<double> Distance(const SurfacePoint& p, const SurfacePoint& q,
                                  std::span<const int32_t> seed_faces = {},
                                  double upper_bound = kInfinity);

  // The exact geodesic from p to q as surface points (p first, then every
  // edge crossing and vertex, q last), of length Distance(p, q, seed_faces).
  // Errors: as Distance, and NotFound when q cannot be reached from p.
  absl::StatusOr<std::vector<SurfacePoint>> Path(const SurfacePoint& p, const SurfacePoint& q,
                                                 std::span<const int32_t> seed_faces = {});

  const ConfinedStats& stats() const { return stats_; }
  // The faces of the last call's last region (any order).
  std::span<const int32_t> region_faces() const { return region_faces_; }
  const Mesh& mesh() const { return mesh_; }

 private:
  // One of `own` (then owned) and `borrowed` is the engine.
  ConfinedGeodesicSolver(std::unique_ptr<ExactGeodesicSolver> own, ExactGeodesicSolver* borrowed,
                         const ConfinedOptions& options);
  void ClearRegion();
  void AddFace(int32_t f);
  // Adds the faces round the vertices in `vertices` (consumed), then round
  // the vertices of the faces that added, `rings` times in all.
  void GrowRings(std::vector<int32_t>& vertices, int32_t rings);
  // Adds a shortest chain of edge-adjacent faces from face `from` to `to`
  // (nothing when they are not connected).
  void AddFaceChain(int32_t from, int32_t to);
  // Adds the faces reached from face `start` through faces that may meet
  // the ellipsoid |x - p| + |x - q| <= length.
  void AddEllipsoid(int32_t start, const mesh::Vec3& p, const mesh::Vec3& q, double length);
  // After a propagation that gave d_R(q) = `distance`: the border edges whose
  // bound falls short of it; appends their ends to `violating_vertices`.
  void FindViolations(const mesh::Vec3& q, double distance,
                      std::vector<int32_t>& violating_vertices);

  const Mesh& mesh_;
  ConfinedOptions options_;
  std::unique_ptr<ExactGeodesicSolver> own_engine_;  // null when borrowed
  ExactGeodesicSolver& engine_;
  // The region: a flag per face and the list of flagged faces.
  std::vector<uint8_t> in_region_;
  std::vector<int32_t> region_faces_;
  // Border half-edges (face in R, twin outside) and their bounds; slot_ maps
  // a half-edge to its index in them, -1 elsewhere.
  std::vector<int32_t> border_;
  std::vector<double> bound_;
  std::vector<int32_t> slot_;
  // Breadth-first search of AddFaceChain: each reached face's predecessor
  // (-2 unreached), and the reached faces to clear.
  std::vector<int32_t> chain_parent_;
  std::vector<int32_t> chain_reached_;
  std::vector<int32_t> ellipsoid_queue_;
  // Per face, the centroid and the largest distance from it to a corner
  // (AddEllipsoid's test), made on the first call that needs them.
  std::vector<std::array<double, 4>> face_ball_;
  std::vector<int32_t> vertices_;
  std::vector<int32_t> next_vertices_;  // GrowRings' next ring
  ConfinedStats stats_;
};

}  // namespace geodex::geodesic
