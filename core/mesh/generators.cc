#include "core/mesh/generators.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

namespace geodex::mesh::gen {
namespace {

// Generators abort on a programming error in their own parameters (asserts
// are compiled out in release builds).
void Check(bool condition, const char* generator, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "geodex::mesh::gen::%s: %s\n", generator, what);
    std::abort();
  }
}

Mesh MustCreate(std::vector<Vec3> positions, std::vector<Triangle> faces, const char* name) {
  absl::StatusOr<Mesh> mesh = Mesh::Create(std::move(positions), std::move(faces), name);
  Check(mesh.ok(), name, mesh.ok() ? "" : std::string(mesh.status().message()).c_str());
  return *std::move(mesh);
}

// Deterministic on every platform (std:: distributions are not).
class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  // Uniform in [0, 1).
  double Uniform() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }

 private:
  uint64_t state_;
};

// Appends the two triangles of the quad (a, b, c, d), counter-clockwise as
// seen from the side its normal points to; `flip` chooses the diagonal (a-c or
// b-d).
void AddQuad(std::vector<Triangle>& faces, int32_t a, int32_t b, int32_t c, int32_t d, bool flip) {
  if (!flip) {
    faces.push_back({a, b, c});
    faces.push_back({a, c, d});
  } else {
    faces.push_back({a, b, d});
    faces.push_back({b, c, d});
  }
}

// A planar grid of nx by ny cells over [0,width]x[0,height] from which the
// cells with keep_cell(i, j) == false are removed; vertices used by no kept
// cell are dropped. Diagonals alternate in a checkerboard.
template <typename KeepCell>
void PlanarGrid(int nx, int ny, double width, double height, KeepCell keep_cell,
                std::vector<Vec3>& positions, std::vector<Triangle>& faces) {
  std::vector<int32_t> id((nx + 1) * (ny + 1), kNone);
  auto used = [&](int i, int j) {
    for (int cj = j - 1; cj <= j; ++cj) {
      for (int ci = i - 1; ci <= i; ++ci) {
        if (ci >= 0 && cj >= 0 && ci < nx && cj < ny && keep_cell(ci, cj)) return true;
      }
    }
    return false;
  };
  const int32_t base = static_cast<int32_t>(positions.size());
  int32_t next = base;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      if (!used(i, j)) continue;
      id[j * (nx + 1) + i] = next++;
      positions.push_back(Vec3(width * i / nx, height * j / ny, 0.0));
    }
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      if (!keep_cell(i, j)) continue;
      const int32_t v00 = id[j * (nx + 1) + i], v10 = id[j * (nx + 1) + i + 1];
      const int32_t v11 = id[(j + 1) * (nx + 1) + i + 1], v01 = id[(j + 1) * (nx + 1) + i];
      AddQuad(faces, v00, v10, v11, v01, (i + j) % 2 == 1);
    }
  }
}

// Appends a unit n-by-n grid shifted by `shift_x` along x.
void UnitGrid(int n, double shift_x, std::vector<Vec3>& positions, std::vector<Triangle>& faces) {
  const size_t first = positions.size();
  PlanarGrid(
      n, n, 1.0, 1.0, [](int, int) { return true; }, positions, faces);
  for (size_t v = first; v < positions.size(); ++v) positions[v].x() += shift_x;
}

}  // namespace

Mesh Grid(int nx, int ny, double width, double height, double jitter, uint32_t seed) {
  Check(nx >= 1 && ny >= 1, "Grid", "nx and ny must be >= 1");
  Check(width > 0 && height > 0, "Grid", "width and height must be > 0");
  Check(jitter >= 0 && jitter < 0.5, "Grid", "jitter must be in [0, 0.5)");
  std::vector<Vec3> positions;
  std::vector<Triangle> faces;
  PlanarGrid(
      nx, ny, width, height, [](int, int) { return true; }, positions, faces);
  if (jitter > 0) {
    SplitMix64 random(seed);
    const double dx = width / nx, dy = height / ny;
    for (int j = 1; j < ny; ++j) {
      for (int i = 1; i < nx; ++i) {
        Vec3& p = positions[j * (nx + 1) + i];
        p.x() += (2 * random.Uniform() - 1) * jitter * dx;
        p.y() += (2 * random.Uniform() - 1) * jitter * dy;
      }
    }
  }
  return MustCreate(std::move(positions), std::move(faces), "Grid");
}

Mesh LShape(int n, double size) {
  Check(n >= 1, "LShape", "n must be >= 1");
  Check(size > 0, "LShape", "size must be > 0");
  std::vector<Vec3> positions;
  std::vector<Triangle> faces;
  PlanarGrid(
      2 * n, 2 * n, size, size, [n](int i, int j) { return i < n || j < n; }, positions, faces);
  return MustCreate(std::move(positions), std::move(faces), "LShape");
}

Mesh SquareWithHole(int n, double size) {
  Check(n >= 3 && n % 3 == 0, "SquareWithHole", "n must be a positive multiple of 3");
  Check(size > 0, "SquareWithHole", "size must be > 0");
  std::vector<Vec3> positions;
  std::vector<Triangle> faces;
  const int a = n / 3, b = 2 * n / 3;
  PlanarGrid(
      n, n, size, size, [a, b](int i, int j) { return !(i >= a && i < b && j >= a && j < b); },
      positions, faces);
  return MustCreate(std::move(positions), std::move(faces), "SquareWithHole");
}

Mesh FoldedSheet(int nx, int ny, double width, double height, double fold_angle) {
  Check(nx >= 2 && nx % 2 == 0, "FoldedSheet", "nx must be even and >= 2");
  Check(ny >= 1, "FoldedSheet", "ny must be >= 1");
  Check(width > 0 && height > 0, "FoldedSheet", "width and height must be > 0");
  std::vector<Vec3> positions;
  std::vector<Triangle> faces;
  PlanarGrid(
      nx, ny, width, height, [](int, int) { return true; }, positions, faces);
  // Rotate the half x > width/2 about the fold line, lifting it towards +z.
  const double c = std::cos(fold_angle), s = std::sin(fold_angle);
  for (int j = 0; j <= ny; ++j) {
    for (int i = nx / 2 + 1; i <= nx; ++i) {
      Vec3& p = positions[j * (nx + 1) + i];
      const double d = width * (i - nx / 2) / nx;
      p.x() = 0.5 * width + d * c;
      p.z() = d * s;
    }
  }
  return MustCreate(std::move(positions), std::move(faces), "FoldedSheet");
}

Mesh Cylinder(int n_around, int n_along, double radius, double length) {
  Check(n_around >= 3 && n_along >= 1, "Cylinder", "needs n_around >= 3 and n_along >= 1");
  Check(radius > 0 && length > 0, "Cylinder", "radius and length must be > 0");
  std::vector<Vec3> positions;
  std::vector<Triangle> faces;
  for (int j = 0; j <= n_along; ++j) {
    for (int k = 0; k < n_around; ++k) {
      const double angle = 2 * std::numbers::pi * k / n_around;
      positions.push_back(
          Vec3(radius * std::cos(angle), radius * std::sin(angle), length * j / n_along));
    }
  }
  auto id = [n_around](int k, int j) { return static_cast<int32_t>(j * n_around + k % n_around); };
  // (around, along) is counter-clockwise seen from outside.
  for (int j = 0; j < n_along; ++j) {
    for (int k = 0; k < n_around; ++k) {
      AddQuad(faces, id(k, j), id(k + 1, j), id(k + 1, j + 1), id(k, j + 1), false);
    }
  }
  return MustCreate(std::move(positions), std::move(faces), "Cylinder");
}

Mesh Cone(int n_around, int n_along, double radius, double height) {
  Check(n_around >= 3 && n_along >= 1, "Cone", "needs n_around >= 3 and n_along >= 1");
  Check(radius > 0 && height > 0, "Cone", "radius and height must be > 0");
  std::vector<Vec3> positions = {Vec3(0, 0, height)};
  std::vector<Triangle> faces;
  for (int j = 1; j <= n_along; ++j) {
    const double t = static_cast<double>(j) / n_along;  // from the apex to the base
    for (int k = 0; k < n_around; ++k) {
      const double angle = 2 * std::numbers::pi * k / n_around;
      positions.push_back(
          Vec3(t * radius * std::cos(angle), t * radius * std::sin(angle), (1 - t) * height));
    }
  }
  auto id = [n_around](int k, int j) {
    return static_cast<int32_t>(1 + (j - 1) * n_around + k % n_around);
  };
  // (around, towards the apex) is counter-clockwise seen from outside.
  for (int k = 0; k < n_around; ++k) faces.push_back({0, id(k, 1), id(k + 1, 1)});
  for (int j = 1; j < n_along; ++j) {
    for (int k = 0; k < n_around; ++k) {
      AddQuad(faces, id(k, j + 1), id(k + 1, j + 1), id(k + 1, j), id(k, j), false);
    }
  }
  return MustCreate(std::move(positions), std::move(faces), "Cone");
}

Mesh Cube(int n, double size) {
  Check(n >= 1, "Cube", "n must be >= 1");
  Check(size > 0, "Cube", "size must be > 0");
  // Lattice points on the surface, shared between the six sides.
  std::map<std::array<int, 3>, int32_t> id;
  std::vector<Vec3> positions;
  auto vertex = [&](std::array<int, 3> c) {
    auto [it, inserted] = id.try_emplace(c, static_cast<int32_t>(positions.size()));
    if (inserted) positions.push_back(Vec3(size * c[0] / n, size * c[1] / n, size * c[2] / n));
    return it->second;
  };
  std::vector<Triangle> faces;
  for (int axis = 0; axis < 3; ++axis) {
    // (u, v, axis) is a right-handed frame: e_u x e_v = e_axis.
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side <= 1; ++side) {
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          std::array<int32_t, 4> q;
          const int corner[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
          for (int c = 0; c < 4; ++c) {
            std::array<int, 3> p;
            p[axis] = side * n;
            p[u] = corner[c][0];
            p[v] = corner[c][1];
            q[c] = vertex(p);
          }
          // Counter-clockwise around +e_axis; reversed on the side facing -e_axis.
          if (side == 1) {
            AddQuad(faces, q[0], q[1], q[2], q[3], (i + j) % 2 == 1);
          } else {
            AddQuad(faces, q[0], q[3], q[2], q[1], (i + j) % 2 == 1);
          }
        }
      }
    }
  }
  return MustCreate(std::move(positions), std::move(faces), "Cube");
}

Mesh Sphere(int subdivisions, double radius) {
  Check(subdivisions >= 0 && subdivisions <= 10, "Sphere", "subdivisions must be in [0, 10]");
  Check(radius > 0, "Sphere", "radius must be > 0");
  // Icosahedron with outward counter-clockwise faces.
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                 {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                 {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Triangle> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Vec3& p : positions) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int32_t, int32_t>, int32_t> midpoint;
    auto mid = [&](int32_t a, int32_t b) {
      const auto key = std::minmax(a, b);
      auto [it, inserted] = midpoint.try_emplace(key, static_cast<int32_t>(positions.size()));
      if (inserted) positions.push_back((positions[a] + positions[b]).normalized());
      return it->second;
    };
    std::vector<Triangle> finer;
    finer.reserve(4 * faces.size());
    for (const Triangle& f : faces) {
      const int32_t ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      finer.push_back({f[0], ab, ca});
      finer.push_back({f[1], bc, ab});
      finer.push_back({f[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    faces = std::move(finer);
  }
  for (Vec3& p : positions) p *= radius;
  return MustCreate(std::move(positions), std::move(faces), "Sphere");
}

namespace {

// A torus whose tube has radius minor_radius(u) at angle u round the axis.
template <typename MinorRadius>
Mesh TorusOf(int n_major, int n_minor, double major_radius, MinorRadius minor_radius,
             const char* name) {
  std::vector<Vec3> positions;
  for (int i = 0; i < n_major; ++i) {
    const double u = 2 * std::numbers::pi * i / n_major;
    const double r = minor_radius(u);
    for (int j = 0; j < n_minor; ++j) {
      const double v = 2 * std::numbers::pi * j / n_minor;
      const double ring = major_radius + r * std::cos(v);
      positions.push_back(Vec3(ring * std::cos(u), ring * std::sin(u), r * std::sin(v)));
    }
  }
  auto id = [&](int i, int j) {
    return static_cast<int32_t>((i % n_major) * n_minor + j % n_minor);
  };
  // d/du x d/dv points away from the tube's core circle: outward.
  std::vector<Triangle> faces;
  for (int i = 0; i < n_major; ++i) {
    for (int j = 0; j < n_minor; ++j) {
      AddQuad(faces, id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1), false);
    }
  }
  return MustCreate(std::move(positions), std::move(faces), name);
}

}  // namespace

Mesh Torus(int n_major, int n_minor, double major_radius, double minor_radius) {
  Check(n_major >= 3 && n_minor >= 3, "Torus", "n_major and n_minor must be >= 3");
  Check(minor_radius > 0 && major_radius > minor_radius, "Torus",
        "needs major_radius > minor_radius > 0");
  return TorusOf(
      n_major, n_minor, major_radius, [&](double) { return minor_radius; }, "Torus");
}

Mesh PinchedTorus(int n_major, int n_minor, double major_radius, double minor_radius_max,
                  double minor_radius_min) {
  Check(n_major >= 3 && n_minor >= 3, "PinchedTorus", "n_major and n_minor must be >= 3");
  Check(minor_radius_min > 0 && minor_radius_max >= minor_radius_min &&
            major_radius > minor_radius_max,
        "PinchedTorus", "needs major_radius > minor_radius_max >= minor_radius_min > 0");
  auto radius = [&](double u) {
    return minor_radius_min + (minor_radius_max - minor_radius_min) * (1 + std::cos(u)) / 2;
  };
  return TorusOf(n_major, n_minor, major_radius, radius, "PinchedTorus");
}

Mesh Dumbbell(int n_around, double sphere_radius, double tube_radius, double tube_length) {
  Check(n_around >= 3, "Dumbbell", "n_around must be >= 3");
  Check(sphere_radius > tube_radius && tube_radius > 0 && tube_length > 0, "Dumbbell",
        "needs sphere_radius > tube_radius > 0 and tube_length > 0");
  // The profile (ring radius, z) from the bottom pole to the top one: the
  // lower sphere up to where it is tube_radius wide, the tube, the upper
  // sphere mirrored.
  const double join = std::numbers::pi - std::asin(tube_radius / sphere_radius);
  const double half = tube_length / 2;
  const double centre = half + sphere_radius * std::cos(std::asin(tube_radius / sphere_radius));
  const int sphere_rings = std::max(2, n_around / 2);
  const double tube_step = 2 * std::numbers::pi * tube_radius / n_around;
  const int tube_rings = std::max(1, static_cast<int>(std::ceil(tube_length / tube_step)));
  std::vector<std::pair<double, double>> profile;
  for (int k = 1; k <= sphere_rings; ++k) {
    const double theta = join * k / sphere_rings;
    profile.push_back({sphere_radius * std::sin(theta), -centre - sphere_radius * std::cos(theta)});
  }
  for (int k = 1; k < tube_rings; ++k) {
    profile.push_back({tube_radius, -half + tube_length * k / tube_rings});
  }
  for (int k = sphere_rings; k >= 1; --k) {
    const double theta = join * k / sphere_rings;
    profile.push_back({sphere_radius * std::sin(theta), centre + sphere_radius * std::cos(theta)});
  }
  std::vector<Vec3> positions = {Vec3(0, 0, -centre - sphere_radius)};
  for (const auto& [rho, z] : profile) {
    for (int j = 0; j < n_around; ++j) {
      const double u = 2 * std::numbers::pi * j / n_around;
      positions.push_back(Vec3(rho * std::cos(u), rho * std::sin(u), z));
    }
  }
  const int32_t top = static_cast<int32_t>(positions.size());
  positions.push_back(Vec3(0, 0, centre + sphere_radius));
  const int rings = static_cast<int>(profile.size());
  auto id = [&](int ring, int j) {
    return static_cast<int32_t>(1 + ring * n_around + j % n_around);
  };
  // Rings run counter-clockwise seen from +z, and z grows ring by ring:
  // these turns point the faces outwards.
  std::vector<Triangle> faces;
  for (int j = 0; j < n_around; ++j) faces.push_back({0, id(0, j + 1), id(0, j)});
  for (int ring = 0; ring + 1 < rings; ++ring) {
    for (int j = 0; j < n_around; ++j) {
      AddQuad(faces, id(ring, j), id(ring, j + 1), id(ring + 1, j + 1), id(ring + 1, j), false);
    }
  }
  for (int j = 0; j < n_around; ++j) faces.push_back({top, id(rings - 1, j), id(rings - 1, j + 1)});
  return MustCreate(std::move(positions), std::move(faces), "Dumbbell");
}

Mesh DoubleTorus(int resolution, double size) {
  Check(resolution >= 1, "DoubleTorus", "resolution must be >= 1");
  Check(size > 0, "DoubleTorus", "size must be > 0");
  // The surface of a slab D x [0, a], where D = [0,5a]x[0,3a] minus the two
  // square holes [a,2a]x[a,2a] and [3a,4a]x[a,2a]: chi = 2 chi(D) = -2, genus 2.
  const int r = resolution;
  const double a = size / 5;
  std::vector<Vec3> positions;
  std::vector<Triangle> top;
  PlanarGrid(
      5 * r, 3 * r, 5 * a, 3 * a,
      [r](int i, int j) {
        const bool in_rows = j >= r && j < 2 * r;
        return !(in_rows && ((i >= r && i < 2 * r) || (i >= 3 * r && i < 4 * r)));
      },
      positions, top);
  const int32_t num_plate = static_cast<int32_t>(positions.size());
  // Layer l in [0, r] lies at z = a l / r: layer r is the top plate (the
  // vertices just made), layer 0 the bottom plate, the others exist only on
  // the boundary.
  for (int32_t v = 0; v < num_plate; ++v) positions[v].z() = a;
  std::vector<Triangle> faces = top;
  for (int32_t v = 0; v < num_plate; ++v) positions.push_back(positions[v] - Vec3(0, 0, a));
  for (const Triangle& t : top) {
    faces.push_back({t[0] + num_plate, t[2] + num_plate, t[1] + num_plate});
  }
  // Boundary edges of D, directed with D on their left (counter-clockwise
  // triangles): those whose reverse is not an edge of another triangle.
  std::map<std::pair<int32_t, int32_t>, int> directed;
  for (const Triangle& t : top) {
    for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
  }
  std::map<std::pair<int32_t, int>, int32_t> wall_vertex;  // (plate vertex, layer) -> id
  auto layer_vertex = [&](int32_t v, int l) -> int32_t {
    if (l == r) return v;
    if (l == 0) return v + num_plate;
    auto [it, inserted] = wall_vertex.try_emplace({v, l}, static_cast<int32_t>(positions.size()));
    if (inserted) positions.push_back(Vec3(positions[v].x(), positions[v].y(), a * l / r));
    return it->second;
  };
  for (const auto& [edge, count] : directed) {
    const auto [p, q] = edge;
    if (directed.count({q, p}) > 0) continue;
    // Quad (p low, q low, q high, p high): its normal (q - p) x e_z points
    // right of p->q, away from D.
    for (int l = 0; l < r; ++l) {
      AddQuad(faces, layer_vertex(p, l), layer_vertex(q, l), layer_vertex(q, l + 1),
              layer_vertex(p, l + 1), l % 2 == 1);
    }
  }
  // Centre the shape at the origin.
  const Vec3 centre(2.5 * a, 1.5 * a, 0.5 * a);
  for (Vec3& p : positions) p -= centre;
  return MustCreate(std::move(positions), std::move(faces), "DoubleTorus");
}

Mesh TwoComponents(int n) {
  Check(n >= 1, "TwoComponents", "n must be >= 1");
  std::vector<Vec3> positions;
  std::vector<Triangle> faces;
  UnitGrid(n, 0.0, positions, faces);
  UnitGrid(n, 2.0, positions, faces);
  return MustCreate(std::move(positions), std::move(faces), "TwoComponents");
}

Mesh SplitFacesInFour(const Mesh& mesh, int times) {
  Check(times >= 0, "SplitFacesInFour", "times must be >= 0");
  if (times == 0) return mesh;
  std::vector<Vec3> positions = mesh.positions();
  std::vector<Triangle> faces;
  faces.reserve(4 * static_cast<size_t>(mesh.num_faces()));
  // One midpoint per edge, shared by the edge's two half-edges.
  std::vector<int32_t> midpoint(mesh.num_halfedges(), kNone);
  for (int32_t h = 0; h < mesh.num_halfedges(); ++h) {
    if (midpoint[h] != kNone) continue;
    midpoint[h] = static_cast<int32_t>(positions.size());
    positions.push_back(0.5 * (mesh.position(mesh.Origin(h)) + mesh.position(mesh.Dest(h))));
    if (mesh.Twin(h) != kNone) midpoint[mesh.Twin(h)] = midpoint[h];
  }
  for (int32_t f = 0; f < mesh.num_faces(); ++f) {
    const Triangle& t = mesh.face(f);
    // Half-edge 3f+i runs from t[i] to t[i+1].
    const int32_t m0 = midpoint[3 * f], m1 = midpoint[3 * f + 1], m2 = midpoint[3 * f + 2];
    faces.push_back({t[0], m0, m2});
    faces.push_back({m0, t[1], m1});
    faces.push_back({m2, m1, t[2]});
    faces.push_back({m0, m1, m2});
  }
  Mesh split = MustCreate(std::move(positions), std::move(faces), mesh.name().c_str());
  return SplitFacesInFour(split, times - 1);
}

}  // namespace geodex::mesh::gen
