#pragma once

// Flat longest-edge bisection: long edges split at their midpoints, so the
// surface, and every exact geodesic distance on it, stays exactly the
// input's. The geodesic sampling picks its samples among mesh vertices, and
// long mesh edges cap how fine that sampling can get; this adds vertices
// where the edges are long without moving the surface.
//
// Longest-edge bisection after M.-C. Rivara, "Algorithms for refining
// triangular grids suitable for adaptive and multigrid techniques", Int. J.
// Numer. Meth. Eng. 20 (1984). Splitting the globally longest edge each time
// means it is the longest edge of both its faces, so the mesh stays
// conforming and the faces keep good shapes (no angle under half the
// smallest angle of the input, Rosenberg and Stenger 1975).
//
// Thread safety: a pure function.

#include <array>
#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"

namespace geodex::mesh {

struct LongEdgeSplit {
  // The split mesh: the input's vertices (same ids, same order), then the
  // new midpoints; the input's name. Face f < input.num_faces() is what is
  // left of input face f (a part of it, or the whole face unsplit), so its
  // corners keep their orientation; later faces are appended pieces.
  Mesh mesh;
  // Per split face: the face of the input mesh it lies in, and where its
  // corners are in that face, as barycentric weights of the parent's corners
  // in the parent's corner order (weights[f][i] = weights of corner i of
  // split face f; each sums to 1, as SurfacePoint::w). Unsplit faces:
  // parent = own id, identity weights.
  std::vector<int32_t> parent;
  std::vector<std::array<std::array<double, 3>, 3>> weights;
  // mesh.num_vertices() minus the input's.
  int32_t new_vertices = 0;
};

// Splits, longest first, every edge longer than `max_edge_length` (mesh
// units) at its midpoint (both faces of an interior edge are split, so the
// mesh stays conforming), until no edge is longer or `max_new_vertices`
// midpoints were added (then it stops, still valid). Ties in length are
// broken by vertex ids, so the result is deterministic. O(E log E) in the
// output's edge count. The output allows zero-area faces: those of the
// input stay so, and halving a sliver can take a piece below the threshold
// Mesh::Create refuses by.
//
// Errors: InvalidArgument for a max_edge_length that is not positive and
// finite, or a negative max_new_vertices; ResourceExhausted when the split
// mesh would have more faces than int32 half-edge ids can number.
absl::StatusOr<LongEdgeSplit> SplitLongEdges(const Mesh& mesh, double max_edge_length,
                                             int32_t max_new_vertices);

}  // namespace geodex::mesh
