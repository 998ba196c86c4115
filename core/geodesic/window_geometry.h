#pragma once

// The plane geometry both exact engines share (ExactGeodesicSolver and
// VertexGeodesicSolver): each half-edge's frame, a window's children across
// its face, the filter by the face's corners, and the classification and
// checks of what a propagation starts from. A window lies on the edge
// of a half-edge h and looks into FaceOf(h): the interval [b0,b1] measured
// from Origin(h), lit by a pseudo-source (sx,sy), sy <= 0, unfolded into h's
// frame at geodesic distance sigma from the source.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/geometry/face_frame.h"
#include "core/mesh/mesh.h"

namespace geodex::geodesic {

// A window is discarded only when a vertex offers a path shorter by more than
// this fraction of the window's own distances, so rounding never discards a
// window that carries a shortest path.
inline constexpr double kFilterSlack = 1e-12;
// Barycentric weights below this count as zero when classifying sources.
inline constexpr double kSnap = 1e-12;

// sqrt(x^2 + y^2): distances here never approach overflow, and std::hypot's
// overflow care costs a third of the propagation time.
inline double Hypot(double x, double y) { return std::sqrt(x * x + y * y); }

// Position of the opposite vertex of a half-edge in that half-edge's frame:
// origin at (0,0), destination at (length,0), face at y > 0.
using HalfEdgeFrame = geometry::FaceFrame;

// Every half-edge's frame (geometry::FrameOfTriangle, from positions). An
// edge of length 0 (two corners at one position, kept by mesh repair)
// carries no window; its frame only has to be free of NaN. cy is kept above
// 0 so that the window formulas never divide by it as 0.
inline std::vector<HalfEdgeFrame> HalfEdgeFrames(const mesh::Mesh& mesh) {
  std::vector<HalfEdgeFrame> frames(mesh.num_halfedges());
  for (int32_t h = 0; h < mesh.num_halfedges(); ++h) {
    const HalfEdgeFrame f =
        geometry::FrameOfTriangle(mesh.position(mesh.Origin(h)), mesh.position(mesh.Dest(h)),
                                  mesh.position(mesh.Opposite(h)));
    frames[h] = f.length > 0 ? HalfEdgeFrame{f.length, f.cx, std::max(f.cy, 1e-300)}
                             : HalfEdgeFrame{0, 0, 1e-300};
  }
  return frames;
}

// 2D coordinates of a point of FaceOf(h) in the frame `f` of half-edge h.
inline std::array<double, 2> InFrame(const HalfEdgeFrame& f, int32_t h,
                                     const mesh::SurfacePoint& p) {
  const int i = h % 3;
  const double wb = p.w[(i + 1) % 3], wc = p.w[(i + 2) % 3];
  return {wb * f.length + wc * f.cx, wc * f.cy};
}

// The part of a window that carries on into the next face, in the frame of
// the half-edge it lands on (the twin of the edge it crosses).
struct ChildWindow {
  double b0, b1;
  double sx, sy;
};

// Where the ray from the pseudo-source through the face's third vertex C
// crosses the window's edge.
inline double RayThroughC(const HalfEdgeFrame& f, double sx, double sy) {
  return sx + (f.cx - sx) * (-sy) / (f.cy - sy);
}

// The rays through [b0,b1] (b1 <= xc, see RayThroughC) leave the face through
// its edge A->C (A = Origin(h)); `child_length` is that edge's length.
inline ChildWindow ChildAcrossAC(const HalfEdgeFrame& f, double child_length, double sx, double sy,
                                 double xc, double b0, double b1) {
  auto hit = [&](double b) {  // fraction along A->C hit by the ray through (b,0)
    if (b >= xc) return 1.0;
    const double den = f.cy * (b - sx) + f.cx * sy;
    if (!(std::abs(den) > 0)) return 0.0;
    return std::clamp(sy * b / den, 0.0, 1.0);
  };
  const double l = child_length;
  const double ux = f.cx / l, uy = f.cy / l;
  return {hit(b0) * l, hit(b1) * l, ux * sx + uy * sy, std::min(ux * sy - uy * sx, 0.0)};
}

// The rays through [b0,b1] (b0 >= xc) leave the face through its edge C->B.
inline ChildWindow ChildAcrossCB(const HalfEdgeFrame& f, double child_length, double sx, double sy,
                                 double xc, double b0, double b1) {
  const double bx = f.length - f.cx, by = -f.cy;  // B - C
  auto hit = [&](double b) {                      // fraction along C->B
    if (b <= xc) return 0.0;
    const double dx = b - sx, dy = -sy;
    const double num = (sx - f.cx) * dy - (sy - f.cy) * dx;
    const double den = bx * dy - by * dx;
    if (!(std::abs(den) > 0)) return 1.0;
    return std::clamp(num / den, 0.0, 1.0);
  };
  const double l = child_length;
  const double ux = bx / l, uy = by / l;
  const double rx = sx - f.cx, ry = sy - f.cy;
  return {hit(b0) * l, hit(b1) * l, ux * rx + uy * ry, std::min(ux * ry - uy * rx, 0.0)};
}

// Whether a corner of the face offers a shorter path to every point of the
// window (Xin & Wang 2009): da, db, dc are the current distances of A, B and
// C. The origin A offers d(A) + |A P| to every point P of [b0,b1]; compared
// with the window's sigma + |S P| the difference only grows with P, so
// checking the far end b1 suffices (B alike at b0). Where d(C) >= sigma the
// set of points that C reaches sooner is convex (bounded by a hyperbola
// branch round C), so both ends inside it put the whole interval inside.
inline bool CornersReachSooner(const HalfEdgeFrame& f, double da, double db, double dc, double b0,
                               double b1, double sx, double sy, double sigma) {
  const double d0 = sigma + Hypot(b0 - sx, sy);
  const double d1 = sigma + Hypot(b1 - sx, sy);
  const double slack = kFilterSlack * std::max(d0, d1);
  if (da + b1 + slack < d1) return true;
  if (db + (f.length - b0) + slack < d0) return true;
  return dc >= sigma && dc + Hypot(b0 - f.cx, f.cy) + slack < d0 &&
         dc + Hypot(b1 - f.cx, f.cy) + slack < d1;
}

// A source point classified for seeding a propagation.
struct SourcePlace {
  enum Kind { kVertex, kEdge, kFace } kind;
  int32_t vertex = mesh::kNone;  // kVertex
  // kEdge and kFace: the weights, normalized, with the zero one exactly 0
  // for an edge; for an edge, `halfedge` is the edge of p.face it lies on.
  std::array<double, 3> w{};
  int32_t halfedge = mesh::kNone;
};

inline SourcePlace ClassifySource(const mesh::Mesh& mesh, const mesh::SurfacePoint& p) {
  int zeros = 0, nonzero = 0, zero = 0;
  for (int i = 0; i < 3; ++i) {
    if (p.w[i] <= kSnap) {
      ++zeros;
      zero = i;
    } else {
      nonzero = i;
    }
  }
  SourcePlace place{SourcePlace::kFace};
  if (zeros >= 2) {
    place.kind = SourcePlace::kVertex;
    place.vertex = mesh.face(p.face)[nonzero];
    return place;
  }
  const double sum = p.w[0] + p.w[1] + p.w[2];
  for (int i = 0; i < 3; ++i) place.w[i] = p.w[i] / sum;
  if (zeros == 1) {
    place.kind = SourcePlace::kEdge;
    place.w[zero] = 0;
    place.halfedge = 3 * p.face + (zero + 1) % 3;  // the edge opposite the zero weight
  }
  return place;
}

// The weights of a point of half-edge h's edge, in the face of h's twin g.
inline std::array<double, 3> WeightsInTwin(int32_t h, int32_t g, const std::array<double, 3>& w) {
  std::array<double, 3> wg = {0, 0, 0};
  wg[g % 3] = w[(h + 1) % 3];  // Origin(g) = Dest(h)
  wg[(g + 1) % 3] = w[h % 3];
  return wg;
}

// Checks a propagation's initial distances: empty, or one non-negative,
// non-NaN value per vertex (+inf allowed). InvalidArgument otherwise.
inline absl::Status CheckInitialDistances(std::span<const double> initial, int32_t num_vertices) {
  if (initial.empty()) return absl::OkStatus();
  if (initial.size() != static_cast<size_t>(num_vertices)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "initial_distance has %d entries, the mesh %d vertices", initial.size(), num_vertices));
  }
  for (int32_t v = 0; v < num_vertices; ++v) {
    if (std::isnan(initial[v]) || initial[v] < 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("initial_distance[%d] = %g is not a distance", v, initial[v]));
    }
  }
  return absl::OkStatus();
}

}  // namespace geodex::geodesic
