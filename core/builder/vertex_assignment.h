#pragma once

// Vertex -> geodesic triangle assignment, the per-vertex part of the index
// (Xin, Ying & He 2012, §4.2: "for each vertex v, output the geodesic triangle
// s1 s2 s3 containing v and the exact geodesic distances d(v, s_i)").
//
// Which triangle contains v is decided here: a vertex of the Voronoi cell of
// sample a goes to the geodesic triangle around a in which its unfolded
// barycentric coordinates (§5.1, core/geometry/planar_unfolding.h) are most inside,
// the triangle whose smallest coordinate is largest. Geodesic triangles are
// curved, so a vertex may lie slightly outside every one; it still gets the
// best and is counted (AssignmentCounts::outside).
//
// Thread safety: reentrant.

#include <cstdint>
#include <vector>

#include "absl/functional/function_ref.h"
#include "core/builder/plan.h"
#include "core/index/index_format.h"
#include "core/mesh/mesh.h"

namespace geodex::builder {

struct AssignmentCounts {
  int64_t referenced = 0;  // vertices with faces and a cell
  int64_t unassigned = 0;  // referenced vertices whose cell has no triangle
  // Assigned vertices whose best coordinates leave [-0.01, 1.01].
  int64_t outside = 0;
};

// Fills `records` (one per vertex of `mesh`) with each referenced vertex's
// triangle (an index into plan.triangles), its corners and the distances
// d(v, corner[i]) as floats; other vertices get triangle = corners = kNone and
// distances 0. `sample_distance(a, b)` is d between samples a and b;
// `vertex_distance(v, b)` is d(v, b) for b the cell of v or a neighbouring
// cell.
AssignmentCounts AssignVerticesToTriangles(
    const mesh::Mesh& mesh, const Plan& plan,
    absl::FunctionRef<double(int32_t a, int32_t b)> sample_distance,
    absl::FunctionRef<double(int32_t v, int32_t b)> vertex_distance,
    std::vector<index::VertexRecord>* records);

}  // namespace geodex::builder
