#include "core/query/engine/internal/o1/lifting.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/geometry/planar_unfolding.h"

namespace geodex::query {
namespace {

using internal::Heaviest;

// Loads the first and last byte of [p, p + size) and discards them: a
// prefetch that works. Software prefetches of the ApproxLifts were found to
// be dropped (still missing L1 several pairs later, on a virtualised Zen 4);
// a load is not. The figures: tests/bench/throughput.md.
inline void Touch(const void* p, size_t size) {
  const char* c = static_cast<const char*>(p);
  asm volatile("" : : "r"(c[0]), "r"(c[size - 1]));
}

using internal::Norm2;

using geometry::Place;
using geometry::Trilaterate;
using geometry::TwoSideDistance2;
using kernel::Frame;
using kernel::Placed;
using kernel::PlaceInTriangle;
using kernel::TwoSideToOutside2;

// Distances from a point of a mesh face to the three corners of a geodesic
// triangle, from the distances d[vertex][corner] of the face's vertices. The
// face lies in its plane (vertex 0 at the origin, vertex 1 at (l, 0), vertex 2
// at (cx, cy)), the point at (px, py). Exact distances of one field at the
// face's corners fix the field's unfolded source in that plane
// (Trilaterate).
inline void LiftInFace(double l, double cx, double cy, double px, double py, bool exact,
                       const double (&d)[3][3], std::array<double, 3>* out) {
  if (exact && cy > 1e-3 * l) {
    for (int c = 0; c < 3; ++c) {
      double sx, sy;
      Trilaterate(l, cx, cy, d[0][c], d[1][c], d[2][c], &sx, &sy);
      (*out)[c] = Norm2(px - sx, py - sy);
    }
    return;
  }
  // Paper §5.2, case 4: two-side unfolding about each edge of the face: the
  // point placed from its distances to the edge's ends, the corner mirrored
  // on the other side; the smallest over the edges. The point's placements
  // do not depend on the corner.
  const double to_vertex[3] = {Norm2(px, py), Norm2(px - l, py), Norm2(px - cx, py - cy)};
  const double edge[3] = {l, Norm2(cx - l, cy), Norm2(cx, cy)};
  double xp[3], yp[3];
  for (int i = 0; i < 3; ++i) {
    if (edge[i] > 0) Place(edge[i], to_vertex[i], to_vertex[(i + 1) % 3], &xp[i], &yp[i]);
  }
  for (int c = 0; c < 3; ++c) {
    double best = kInf;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      if (!(edge[i] > 0)) {
        best = std::min(best, (to_vertex[i] + d[i][c]) * (to_vertex[i] + d[i][c]));
        continue;
      }
      double xq, yq;
      Place(edge[i], d[i][c], d[j][c], &xq, &yq);
      best = std::min(best, TwoSideDistance2(xp[i], yp[i], xq, yq));
    }
    (*out)[c] = std::sqrt(best);
  }
}

}  // namespace

Lifting::Lifting(const MeshView& view, std::span<const index::VertexRecord> records,
                 const LiftedUnfolding& unfolding)
    : view_(view), records_(records), unfolding_(&unfolding) {
  face_lifts_.resize(view_.faces.size() / 3);
  for (size_t f = 0; f < face_lifts_.size(); ++f) {
    face_lifts_[f] = MakeFaceLift(static_cast<int32_t>(f));
  }
}

bool Lifting::FaceDistances(const int32_t* f, const LiftedPoint& anchor, double (&d)[3][3]) const {
  // Exact for vertices of the anchor triangle, case 2.2 for the others.
  bool exact = true;
  for (int i = 0; i < 3; ++i) {
    const index::VertexRecord& r = records_[f[i]];
    if (r.triangle == anchor.triangle) {
      for (int c = 0; c < 3; ++c) d[i][c] = r.distance[c];
      continue;
    }
    exact = false;
    const LiftedPoint vi = VertexLift(f[i]);
    const Frame<double>* frames = unfolding_->Frames(vi.triangle);
    const Placed<double> placed = PlaceInTriangle(frames, vi.distance.data());
    for (int c = 0; c < 3; ++c) {
      const int32_t s = anchor.corner[c];
      d[i][c] = -1;
      for (int j = 0; j < 3; ++j) {
        if (vi.corner[j] == s) d[i][c] = vi.distance[j];
      }
      if (d[i][c] < 0) {
        const double e[3] = {unfolding_->Matrix(s, vi.corner[0]),
                             unfolding_->Matrix(s, vi.corner[1]),
                             unfolding_->Matrix(s, vi.corner[2])};
        d[i][c] = std::sqrt(TwoSideToOutside2(frames, placed, e));
      }
    }
  }
  return exact;
}

Lifting::FaceFrame Lifting::FaceFrameOf(const int32_t* f) const {
  // The face in its own plane: v0 at the origin, v1 on the x axis.
  return geometry::FrameOfTriangle(view_.Position(f[0]), view_.Position(f[1]),
                                   view_.Position(f[2]));
}

// Anchor on the geodesic triangle most of the face's vertices share (fewer
// approximate distances); when all three differ, on the triangle of the
// point's heaviest vertex (three ApproxLifts).
Lifting::FaceLift Lifting::MakeFaceLift(int32_t face) {
  const int32_t* f = &view_.faces[3 * face];
  FaceLift out;
  const FaceFrame frame = FaceFrameOf(f);
  const double edge[3] = {frame.length, std::hypot(frame.cx - frame.length, frame.cy),
                          std::hypot(frame.cx, frame.cy)};
  if (!(edge[0] > 0 && edge[1] > 0 && edge[2] > 0)) return out;  // SlowLift
  out.l = frame.length;
  out.cx = frame.cx;
  out.cy = frame.cy;
  const int32_t t0 = records_[f[0]].triangle, t1 = records_[f[1]].triangle,
                t2 = records_[f[2]].triangle;
  if (t0 != t1 && t0 != t2 && t1 != t2) {
    out.approx = static_cast<int32_t>(approx_lifts_.size());
    out.anchors = 3;
    for (int k = 0; k < 3; ++k) approx_lifts_.push_back(MakeApproxLift(f, frame, k));
    out.triangle = approx_lifts_[out.approx].triangle;
    return out;
  }
  const int k = t0 == t1 || t0 == t2 ? 0 : 1;
  const LiftedPoint anchor = VertexLift(f[k]);
  out.triangle = anchor.triangle;
  for (int c = 0; c < 3; ++c) out.corner[c] = anchor.corner[c];
  double d[3][3];
  if (FaceDistances(f, anchor, d) && frame.cy > 1e-3 * frame.length) {
    for (int c = 0; c < 3; ++c) {
      double sx, sy;
      Trilaterate(frame.length, frame.cx, frame.cy, d[0][c], d[1][c], d[2][c], &sx, &sy);
      out.src[c][0] = sx;
      out.src[c][1] = sy;
    }
    return out;
  }
  out.approx = static_cast<int32_t>(approx_lifts_.size());
  out.anchors = 1;
  approx_lifts_.push_back(MakeApproxLift(f, frame, k));
  return out;
}

Lifting::ApproxLift Lifting::MakeApproxLift(const int32_t* f, const FaceFrame& frame, int k) const {
  const LiftedPoint anchor = VertexLift(f[k]);
  ApproxLift out;
  out.triangle = anchor.triangle;
  for (int c = 0; c < 3; ++c) out.corner[c] = anchor.corner[c];
  double d[3][3];
  FaceDistances(f, anchor, d);
  // Paper §5.2, case 4: corner c unfolded about face edge i (vertex i to
  // vertex i+1) from its distances to the edge's ends, on the far side of the
  // edge (two-side), in the face's plane.
  const double vx[3] = {0, frame.length, frame.cx}, vy[3] = {0, 0, frame.cy};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const double len = std::hypot(vx[j] - vx[i], vy[j] - vy[i]);
    const double ux = (vx[j] - vx[i]) / len, uy = (vy[j] - vy[i]) / len;
    // (-uy, ux) points into the face: it is counter-clockwise (cy > 0).
    for (int c = 0; c < 3; ++c) {
      double x, y;
      Place(len, d[i][c], d[j][c], &x, &y);
      out.image[c][i][0] = static_cast<float>(vx[i] + x * ux + y * uy);
      out.image[c][i][1] = static_cast<float>(vy[i] + x * uy - y * ux);
    }
  }
  return out;
}

void Lifting::PrefetchFace(const SurfacePoint& p) const {
  __builtin_prefetch(&view_.faces[3 * p.face]);
  __builtin_prefetch(&face_lifts_[p.face]);
}

void Lifting::PrefetchLift(const SurfacePoint& p) const {
  const int k = Heaviest(p);
  const FaceLift& fl = face_lifts_[p.face];
  if (p.w[k] >= 1.0 || fl.triangle < 0) {
    __builtin_prefetch(&records_[view_.faces[3 * p.face + k]]);
  } else if (fl.approx >= 0) {
    const char* line = reinterpret_cast<const char*>(&ApproxLiftOf(fl, k));
    Touch(line, sizeof(ApproxLift));
  }
}

LiftedPoint Lifting::SlowLift(const SurfacePoint& p, int heaviest) const {
  const int32_t* f = &view_.faces[3 * p.face];
  const int32_t t0 = records_[f[0]].triangle, t1 = records_[f[1]].triangle,
                t2 = records_[f[2]].triangle;
  int k = heaviest;
  if (t0 == t1 || t0 == t2) {
    k = 0;
  } else if (t1 == t2) {
    k = 1;
  }
  LiftedPoint out = VertexLift(f[k]);
  double d[3][3];
  const bool exact = FaceDistances(f, out, d);
  const FaceFrame frame = FaceFrameOf(f);
  LiftInFace(frame.length, frame.cx, frame.cy, p.w[1] * frame.length + p.w[2] * frame.cx, p.w[2] * frame.cy,
             exact, d, &out.distance);
  return out;
}

double O1Distance(const MeshView& view, const Lifting& lifting, const LiftedUnfolding& unfolding,
                  const SurfacePoint& p, const SurfacePoint& q) {
  const LiftedPoint a = lifting.Lift(p), b = lifting.Lift(q);
  const double d = unfolding.Distance(a, b);
  return unfolding.AreNear(a, b) ? std::max(d, (view.PositionOf(p) - view.PositionOf(q)).norm())
                                 : d;
}

}  // namespace geodex::query
