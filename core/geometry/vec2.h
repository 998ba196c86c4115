#pragma once

// The one 2D vector of core: a point or direction in the plane of an
// unfolding (query/strip_funnel.h), a tangent plane (geodesic polar
// coordinates round a point) or a face's own frame
// (triangulation/geodesic_edges.cc). Eigen's fixed-size vector, as
// mesh::Vec3 is for 3D: its arithmetic is element by element, in the order
// written, so results round as the same formulas on two doubles do.
//
// Thread safety: a value type and a pure function.

#include <Eigen/Core>

namespace geodex::geometry {

using Vec2 = Eigen::Vector2d;

// The cross product of a and b taken as vectors in the xy plane (its z
// component): positive when b turns counter-clockwise from a.
inline double Cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

}  // namespace geodex::geometry
