#pragma once

// CGAL's exact geodesics (Surface_mesh_shortest_path, CGAL 5.5.1, with the
// Exact_predicates_inexact_constructions_kernel on a Surface_mesh) behind an
// interface that speaks geodex ids, for cross-checks and benchmarks. CGAL
// implements the same family of algorithms as ours (Xin & Wang's improved
// Chen-Han), independently: the reference for tests/integration and
// tests/bench. Not part of any installed library.
//
// CGAL 5.5.1 pitfalls, measured by us, and what this wrapper does about them:
//  (1) A source lying exactly on an edge is placed at its mirror image along
//      that edge. Distances() therefore accepts only sources at a vertex,
//      strictly inside a face, or at the exact midpoint of an edge (its own
//      mirror image), and returns InvalidArgument for any other edge point.
//  (2) For a face added as (v0, v1, v2), CGAL's barycentric coordinates are
//      in the order (v2, v0, v1). We do not hard-code that: BarycentricOrder()
//      reads the order off the Surface_mesh (the source vertex of the i-th
//      half-edge from halfedge(f)), and Distances() permutes the weights
//      accordingly; a cross-check test verifies the (v2, v0, v1) claim and the
//      conversion with a source near one corner.
//  (3) Unreferenced vertices crash it. The Surface_mesh is built from the
//      referenced vertices only; unreferenced ones get +inf.
//  (4) Its sequence tree is large (~9 GB on the 134k-vertex Igea): callers
//      decide which meshes are affordable.
//
// Example:
//   GEODEX_ASSIGN_OR_RETURN(auto cgal, CgalShortestPaths::Create(mesh));
//   GEODEX_ASSIGN_OR_RETURN(std::vector<double> d, cgal->Distances(source));
//
// Thread safety: not thread-safe (CGAL keeps per-query state); one object per
// thread. `mesh` must outlive the object.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"

namespace geodex::cgal_reference {

class CgalShortestPaths {
 public:
  // Copies the referenced vertices and all faces of `mesh` into a CGAL
  // Surface_mesh. Errors: InvalidArgument if CGAL refuses a face (cannot
  // happen for a valid geodex Mesh, which is manifold and consistently
  // oriented).
  static absl::StatusOr<std::unique_ptr<CgalShortestPaths>> Create(const mesh::Mesh& mesh);

  ~CgalShortestPaths();
  CgalShortestPaths(const CgalShortestPaths&) = delete;
  CgalShortestPaths& operator=(const CgalShortestPaths&) = delete;

  // Exact geodesic distance from `source` to every vertex, indexed by geodex
  // vertex id; +inf for unreferenced vertices and for vertices CGAL cannot
  // reach (another connected component). Builds CGAL's sequence tree, which is
  // kept until the next call or Release(). Errors: InvalidArgument /
  // OutOfRange for an invalid point (see mesh::ValidateSurfacePoint) and
  // InvalidArgument for a point on an edge other than its midpoint (pitfall 1).
  absl::StatusOr<std::vector<double>> Distances(const mesh::SurfacePoint& source);

  // Frees CGAL's sequence tree.
  void Release();

  // The geodex vertex ids of face `f` in the order of CGAL's barycentric
  // coordinates for that face.
  std::array<int32_t, 3> BarycentricOrder(int32_t f) const;

  // Number of vertices in the CGAL mesh (the referenced ones).
  int32_t num_cgal_vertices() const;

 private:
  struct Impl;
  explicit CgalShortestPaths(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace geodex::cgal_reference
