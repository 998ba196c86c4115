#pragma once

// The per-face lifting data QueryEngine derives when it loads an index:
// internal to core/query (query_engine.cc), kept out of query_engine.h so
// that it shows the public contract.
//
// Lifting of a face's interior points is derived at load so that a lift
// costs one or two cache-line loads and no unfolding. The face lies in its
// plane (vertex 0 at the origin, vertex 1 at (l, 0), vertex 2 at (cx, cy)).
//  - Exact faces (all three vertices in the anchor triangle): per corner c,
//    the unfolded source of the corner's field, src[c], trilaterated from
//    the vertices' exact distances; a distance is |point - src[c]|.
//  - Approximate faces (a vertex outside the anchor triangle, or a sliver):
//    the paper's two-side unfolding (§5.2, case 4) about each face edge
//    puts corner c at a fixed image beyond the edge; the distance is the
//    smallest over the three images (ApproxLift). Faces whose vertices lie
//    in three different triangles take the anchor of the point's heaviest
//    vertex, so they keep three ApproxLifts.
//  - triangle -1: lifted by QueryEngine::SlowLift (faces with a zero-length
//    edge).

#include <cstdint>

namespace geodex::query::internal {

// One per mesh face, one cache line: the first load of a lift.
struct alignas(64) FaceLift {
  int32_t triangle = -1;
  int32_t corner[3] = {-1, -1, -1};
  float l = 0, cx = 0, cy = 0;
  int32_t approx = -1;  // first ApproxLift, or -1 for an exact face
  int32_t anchors = 0;  // ApproxLifts of the face: 1, or 3 (by heaviest vertex)
  float src[3][2] = {};
};
static_assert(sizeof(FaceLift) == 64);

// The corner images of an approximate face, for one anchor triangle.
struct ApproxLift {
  int32_t triangle;
  int32_t corner[3];
  float image[3][3][2];  // [corner][face edge] = (x, y) in the face's plane
};

// A face in its own plane, in double precision (FaceLift keeps floats).
struct FaceFrame {
  double l, cx, cy;
};

}  // namespace geodex::query::internal
