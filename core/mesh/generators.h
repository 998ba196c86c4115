#pragma once

// Meshes generated in code, for tests and benchmarks that must not depend on
// data files. Every generator is deterministic and returns a valid Mesh
// (it aborts on a programming error in its own parameters).

#include <cstdint>

#include "core/mesh/mesh.h"

namespace geodex::mesh::gen {

// Flat grid in the z=0 plane covering [0,width]x[0,height], nx by ny cells,
// each cell split in two triangles (diagonals alternate). `jitter` (fraction of
// a cell, < 0.5) moves interior vertices in the plane, pseudo-randomly from
// `seed`. Geodesic distance = Euclidean distance (the domain is convex).
Mesh Grid(int nx, int ny, double width, double height, double jitter = 0.0, uint32_t seed = 1);

// L-shaped flat domain: the square [0,2]x[0,2] minus [1,2]x[1,2], scaled by
// `size`/2, with `n` cells per unit of the scaled half-size. The re-entrant
// corner is the vertex at (size/2, size/2, 0).
Mesh LShape(int n, double size);

// Flat square [0,size]^2 with a square hole [size/3, 2size/3]^2, n cells a side
// (n divisible by 3).
Mesh SquareWithHole(int n, double size);

// Grid(nx, ny, width, height) folded along the line x = width/2 by
// `fold_angle` radians (0 = flat): developable, so geodesic distances equal
// the distances in the unfolded plane. nx must be even.
Mesh FoldedSheet(int nx, int ny, double width, double height, double fold_angle);

// Open cylinder of `radius` around the z axis, z in [0, length], n_around
// segments around and n_along along. Developable.
Mesh Cylinder(int n_around, int n_along, double radius, double length);

// Open cone (a pyramid over a regular n_around-gon, so each side is flat)
// with its apex at (0, 0, height) and its base circle of `radius` in z = 0,
// n_along rings of vertices below the apex. Developable away from the apex.
Mesh Cone(int n_around, int n_along, double radius, double height);

// Closed cube surface [0,size]^3, n cells per face side.
Mesh Cube(int n, double size);

// Icosphere of `radius` with `subdivisions` loop subdivisions (vertices
// projected to the sphere): 20*4^subdivisions faces.
Mesh Sphere(int subdivisions, double radius);

// Torus around the z axis: major radius R, minor radius r.
Mesh Torus(int n_major, int n_minor, double major_radius, double minor_radius);

// Torus whose tube radius shrinks round the major circle: minor_radius_max
// at angle 0 (the +x side), minor_radius_min opposite it, varying as
// (1 + cos u) / 2 between. With minor_radius_max near major_radius it is a
// blob with a thin handle; with minor_radius_min a few edge lengths, a torus
// pinched almost shut. Needs major_radius > minor_radius_max >=
// minor_radius_min > 0.
Mesh PinchedTorus(int n_major, int n_minor, double major_radius, double minor_radius_max,
                  double minor_radius_min);

// Two spheres of `sphere_radius` on the z axis joined by a tube of
// `tube_radius` and `tube_length` between them (a surface of revolution,
// genus 0), n_around vertices round every ring; the tube's rings are spaced
// about as far apart as its vertices round it. Needs sphere_radius >
// tube_radius > 0, tube_length > 0, n_around >= 3.
Mesh Dumbbell(int n_around, double sphere_radius, double tube_radius, double tube_length);

// Closed genus-2 surface (two tori joined), roughly `size` across.
Mesh DoubleTorus(int resolution, double size);

// `mesh` with every face split in four at its edge midpoints (flat: the new
// vertices lie on the old edges), repeated `times` times. The surface, and so
// every exact geodesic distance between its points, is unchanged; the vertex
// count grows about fourfold per split. The input's vertices keep their ids.
Mesh SplitFacesInFour(const Mesh& mesh, int times = 1);

// Two disjoint unit grids (n by n cells), the second shifted by 2 along x.
Mesh TwoComponents(int n);

}  // namespace geodex::mesh::gen
