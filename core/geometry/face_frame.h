#pragma once

// A triangle laid into its own plane, written once: the frame the exact
// engines (geodesic/window_geometry.h), the lifting (query lifting.h), the
// geodesic edges' crossing test (triangulation/geodesic_edges.cc) and the
// strip unfolding (query strip_funnel.h) all start from.
//
// The apex's height is taken from the cross product, |ab x ac| / |ab|, not
// from the law of cosines sqrt(|ac|^2 - cx^2): on a sliver triangle cx is
// close to |ac| and the subtraction cancels half the digits of the height,
// while the cross product keeps them.
//
// Thread safety: a value type and a pure function.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace geodex::geometry {

// Triangle (a, b, c) in its own plane: a at the origin, b at (length, 0),
// c at (cx, cy) with cy >= 0.
struct FaceFrame {
  double length;
  double cx;
  double cy;
};

// The frame of the triangle with corners at positions a, b, c. For a = b
// (length 0) cx and cy are NaN: callers that keep such faces test length.
inline FaceFrame FrameOfTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                 const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a;
  const double l = ab.norm();
  return {l, ab.dot(ac) / l, ab.cross(ac).norm() / l};
}

}  // namespace geodex::geometry
