#pragma once

// A lower bound on the geodesic distance between two points, tighter than
// the chord on curved parts of a surface, that certifies a near pair's walk
// without an exact propagation (refinement.h).
//
// Every surface path from p to q leaves any set of faces S that holds p and
// not q, across an edge of S's border, at some point x; it is then at least
// |p - x| + |x - q| long, two chords. So the geodesic is at least the least
// of that sum over S's border, and on one edge that least sum is the
// distance between p and q turned about the edge's line into one plane, on
// either side of it (clamped to the edge's ends): a few flops an edge.
// Where the surface bends between the points the two chords follow it
// better than one: on a patch of curvature radius R a geodesic of length s
// exceeds its chord by about s^3 / 24R^2 and the two chords through its
// middle by a quarter of that; across one sharp edge the bound is exact.
//
// S is grown from p's faces over the faces nearer p than q (so its border
// runs along the bisector, through the middle of the path) inside the
// ellipsoid |p - c| + |c - q| <= reach: a border edge on the ellipsoid gives
// about `reach`, so the bound never falls below min(reach, the bisector's)
// by more than the span of a face.
//
// Thread safety: a pure function of immutable data and the caller's scratch.

#include <cstdint>

#include "core/query/engine/internal/paths/walk_scratch.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

// The least of |p - x| + |x - q| over the points x of the segment [a, b].
double TwoChordLength(const mesh::Vec3& p, const mesh::Vec3& q, const mesh::Vec3& a,
                      const mesh::Vec3& b);

// A lower bound on the geodesic distance between valid canonical points p
// and q, at least their chord, from the border of the faces nearer p than q
// within the ellipsoid of `reach` round them (above). Visits at most
// `max_faces` faces; a region that would grow past them gives the chord. The
// region's memory is the scratch's.
double CutLowerBound(const MeshView& view, const SurfacePoint& p, const SurfacePoint& q,
                     double reach, int max_faces, WalkScratch* scratch);

}  // namespace geodex::query
