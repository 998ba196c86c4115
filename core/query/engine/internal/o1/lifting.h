#pragma once

// Lifting a surface point into a geodesic triangle (Xin, Ying & He 2012,
// §5.1): its triangle T and its distances to T's three corner samples. A
// vertex's lift is its index record (exact). A point inside a mesh face is
// lifted from the face vertices' distances, which are exact when a vertex
// lies in T and come from case 2.2 of the unfolding (unfolding.h) otherwise.
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
//  - triangle -1: lifted by Lifting::SlowLift (faces with a zero-length
//    edge).
//
// Thread safety: immutable after construction; every method is const and
// thread-safe.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "core/geometry/face_frame.h"
#include "core/index/index.h"
#include "core/query/engine/internal/o1/lifted_unfolding.h"
#include "core/query/engine/mesh_view.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

namespace internal {

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
using FaceFrame = geometry::FaceFrame;

}  // namespace internal

class Lifting {
 public:
  // Derives the per-face lifting data of the mesh `view` whose vertices have
  // `records` (O(faces)). The arrays and `unfolding` must outlive this object.
  Lifting(const MeshView& view, std::span<const index::VertexRecord> records,
          const LiftedUnfolding& unfolding);

  // The lift of a valid point (see the header comment).
  LiftedPoint Lift(const SurfacePoint& p) const;
  // The lift of vertex v: its record, with its triangle's corners (-1
  // without a triangle).
  LiftedPoint VertexLift(int32_t v) const {
    const index::VertexRecord& r = records_[v];
    LiftedPoint out{r.triangle, {-1, -1, -1}, {r.distance[0], r.distance[1], r.distance[2]}};
    if (r.triangle >= 0) {
      const index::GeodesicTriangle& t = unfolding_->Triangle(r.triangle);
      out.corner = {t.corner[0], t.corner[1], t.corner[2]};
    }
    return out;
  }
  // Bring in what Lift(p) reads: the face and its FaceLift (prefetched),
  // then, once those are in cache, the ApproxLift (loaded: see Touch in the
  // .cc) or the vertex record (prefetched).
  void PrefetchFace(const SurfacePoint& p) const;
  void PrefetchLift(const SurfacePoint& p) const;

 private:
  using FaceLift = internal::FaceLift;
  using ApproxLift = internal::ApproxLift;
  using FaceFrame = internal::FaceFrame;

  // The ApproxLift a point of an approximate face uses; `heaviest` is its
  // face vertex of largest weight.
  const ApproxLift& ApproxLiftOf(const FaceLift& fl, int heaviest) const;
  // The ApproxLift of `face` anchored on the triangle of its vertex `k`.
  ApproxLift MakeApproxLift(const int32_t* face_vertices, const FaceFrame& frame, int k) const;
  FaceFrame FaceFrameOf(const int32_t* face_vertices) const;
  // Distances from a face's vertices to the anchor's corners; true when all
  // are exact (the vertices lie in the anchor triangle).
  bool FaceDistances(const int32_t* face_vertices, const LiftedPoint& anchor,
                     double (&d)[3][3]) const;
  // Appends the face's ApproxLifts to approx_lifts_ when it has any.
  FaceLift MakeFaceLift(int32_t face);
  // Lifts a point of a face without a FaceLift; `heaviest` is the face
  // vertex of largest weight (the anchor when the vertices share none).
  LiftedPoint SlowLift(const SurfacePoint& p, int heaviest) const;

  MeshView view_;
  std::span<const index::VertexRecord> records_;
  const LiftedUnfolding* unfolding_;
  std::vector<FaceLift> face_lifts_;      // one per face
  std::vector<ApproxLift> approx_lifts_;  // of the approximate faces
};

// Inline: on the path of every query.

namespace internal {

// The face vertex of largest weight: the anchor of points of faces whose
// vertices lie in three different triangles.
inline int Heaviest(const SurfacePoint& p) {
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (p.w[i] > p.w[k]) k = i;
  }
  return k;
}

// sqrt(x^2 + y^2) without std::hypot's overflow care, which costs more than
// the rest of a query.
inline double Norm2(double x, double y) { return std::sqrt(x * x + y * y); }

}  // namespace internal

inline const Lifting::ApproxLift& Lifting::ApproxLiftOf(const FaceLift& fl, int heaviest) const {
  return approx_lifts_[fl.approx + (fl.anchors == 3 ? heaviest : 0)];
}

inline LiftedPoint Lifting::Lift(const SurfacePoint& p) const {
  const int k = internal::Heaviest(p);
  if (p.w[k] >= 1.0) return VertexLift(view_.faces[3 * p.face + k]);  // at a vertex: exact record
  const FaceLift& fl = face_lifts_[p.face];
  if (fl.triangle < 0) return SlowLift(p, k);
  const double px = p.w[1] * fl.l + p.w[2] * fl.cx, py = p.w[2] * fl.cy;
  LiftedPoint out;
  if (fl.approx < 0) {
    out.triangle = fl.triangle;
    for (int c = 0; c < 3; ++c) {
      out.corner[c] = fl.corner[c];
      out.distance[c] = internal::Norm2(px - fl.src[c][0], py - fl.src[c][1]);
    }
    return out;
  }
  const ApproxLift& al = ApproxLiftOf(fl, k);
  out.triangle = al.triangle;
  for (int c = 0; c < 3; ++c) {
    out.corner[c] = al.corner[c];
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      const double dx = px - al.image[c][i][0], dy = py - al.image[c][i][1];
      best = std::min(best, dx * dx + dy * dy);
    }
    out.distance[c] = std::sqrt(best);
  }
  return out;
}

// The O(1) answer of §5 for valid points, as they are (not made canonical):
// both lifted, then unfolded; for near pairs (LiftedUnfolding::AreNear) at least
// the straight-line distance, as no surface path is shorter.
double O1Distance(const MeshView& view, const Lifting& lifting, const LiftedUnfolding& unfolding,
                  const SurfacePoint& p, const SurfacePoint& q);

}  // namespace geodex::query
