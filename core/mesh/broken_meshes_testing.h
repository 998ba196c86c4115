#pragma once

// Broken meshes generated in code, one per kind of repair (and the
// unrepairable Möbius strip), for the tests of core/mesh/mesh_repair.h and of
// the queries over repaired indexes. Test-only, header-only.

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/mesh/generators.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"

namespace geodex::mesh::testing {

// A valid mesh's arrays as a raw mesh.
inline RawMesh RawOf(const Mesh& mesh, std::string name) {
  RawMesh raw;
  raw.name = std::move(name);
  raw.positions = mesh.positions();
  raw.triangles = mesh.faces();
  for (int32_t f = 0; f < mesh.num_faces(); ++f) raw.input_face.push_back(f);
  return raw;
}

inline void AddTriangle(RawMesh* raw, Triangle t) {
  raw->input_face.push_back(static_cast<int32_t>(raw->triangles.size()));
  raw->triangles.push_back(t);
}

// Triangles of a convex solid, each turned so that its normal points away
// from `inside`.
inline void AddOutward(RawMesh* raw, std::vector<Triangle> triangles, const Vec3& inside) {
  for (Triangle t : triangles) {
    const Vec3 &a = raw->positions[t[0]], &b = raw->positions[t[1]], &c = raw->positions[t[2]];
    if ((b - a).cross(c - a).dot((a + b + c) / 3 - inside) < 0) std::swap(t[1], t[2]);
    AddTriangle(raw, t);
  }
}

// The closed box [lo, hi] with 12 outward triangles over the vertex ids
// `corner` (corner x + 2y + 4z of the box), whose positions must be set.
inline void AddBox(RawMesh* raw, const int32_t (&corner)[8], const Vec3& lo, const Vec3& hi) {
  const int quads[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                           {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  std::vector<Triangle> triangles;
  for (const auto& q : quads) {
    triangles.push_back({corner[q[0]], corner[q[1]], corner[q[2]]});
    triangles.push_back({corner[q[0]], corner[q[2]], corner[q[3]]});
  }
  AddOutward(raw, triangles, (lo + hi) / 2);
}

inline int32_t AddVertex(RawMesh* raw, const Vec3& p) {
  raw->positions.push_back(p);
  return static_cast<int32_t>(raw->positions.size() - 1);
}

// Two closed unit cubes touching along one edge, x = y = 1: [0,1]^3 and
// [1,2]x[1,2]x[0,1]. The edge has four faces (a non-manifold edge) and its
// ends are non-manifold vertices.
inline RawMesh TwoCubesSharingAnEdge() {
  RawMesh raw;
  raw.name = "two cubes";
  int32_t a[8], b[8];
  for (int c = 0; c < 8; ++c) {
    a[c] = AddVertex(&raw, Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1));
  }
  for (int c = 0; c < 8; ++c) {
    const bool shared = (c & 3) == 0;  // x = y = 1 of the second cube
    b[c] = shared ? a[3 + (c & 4)]
                  : AddVertex(&raw, Vec3(1 + (c & 1), 1 + ((c >> 1) & 1), (c >> 2) & 1));
  }
  AddBox(&raw, a, Vec3(0, 0, 0), Vec3(1, 1, 1));
  AddBox(&raw, b, Vec3(1, 1, 0), Vec3(2, 2, 1));
  return raw;
}

// Three square pages, two triangles each, bound along the spine from vertex
// 0 (the origin) to vertex 1 (0, 0, 1), at 0, 120 and 240 degrees round it,
// all running the spine from 1 to 0: a non-manifold edge of three faces that
// no two pages enclose a solid at.
inline RawMesh BookOfThreeSheets() {
  RawMesh raw;
  raw.name = "book";
  AddVertex(&raw, Vec3(0, 0, 0));
  AddVertex(&raw, Vec3(0, 0, 1));
  for (int k = 0; k < 3; ++k) {
    const double angle = 2 * std::numbers::pi * k / 3;
    const Vec3 out(std::cos(angle), std::sin(angle), 0);
    const int32_t p = AddVertex(&raw, out), q = AddVertex(&raw, out + Vec3(0, 0, 1));
    AddTriangle(&raw, {0, p, q});
    AddTriangle(&raw, {0, q, 1});
  }
  return raw;
}

// Two closed square pyramids touching apex to apex at the origin (vertex 0):
// one non-manifold vertex with two fans.
inline RawMesh TwoPyramidsApexToApex() {
  RawMesh raw;
  raw.name = "two pyramids";
  AddVertex(&raw, Vec3(0, 0, 0));
  for (double side : {-1.0, 1.0}) {
    int32_t base[4];
    for (int k = 0; k < 4; ++k) {
      const double angle = std::numbers::pi / 2 * k;
      base[k] = AddVertex(&raw, Vec3(std::cos(angle), std::sin(angle), side));
    }
    AddOutward(&raw,
               {{0, base[0], base[1]},
                {0, base[1], base[2]},
                {0, base[2], base[3]},
                {0, base[3], base[0]},
                {base[0], base[1], base[2]},
                {base[0], base[2], base[3]}},
               Vec3(0, 0, side / 2));
  }
  return raw;
}

// Two triangles sharing only vertex 0: a bowtie.
inline RawMesh Bowtie() {
  RawMesh raw;
  raw.name = "bowtie";
  AddVertex(&raw, Vec3(0, 0, 0));
  AddVertex(&raw, Vec3(1, -0.5, 0));
  AddVertex(&raw, Vec3(1, 0.5, 0));
  AddVertex(&raw, Vec3(-1, 0.5, 0));
  AddVertex(&raw, Vec3(-1, -0.5, 0));
  AddTriangle(&raw, {0, 1, 2});
  AddTriangle(&raw, {0, 3, 4});
  return raw;
}

// A Möbius strip: n quads round a circle of radius 2, width 1, half a turn.
inline RawMesh MobiusStrip(int n = 24) {
  RawMesh raw;
  raw.name = "mobius";
  for (int i = 0; i < n; ++i) {
    const double t = 2 * std::numbers::pi * i / n;
    const Vec3 centre(2 * std::cos(t), 2 * std::sin(t), 0);
    const Vec3 across =
        std::cos(t / 2) * Vec3(std::cos(t), std::sin(t), 0) + std::sin(t / 2) * Vec3(0, 0, 1);
    AddVertex(&raw, centre + 0.5 * across);
    AddVertex(&raw, centre - 0.5 * across);
  }
  for (int i = 0; i < n; ++i) {
    const int32_t top = 2 * i, bottom = 2 * i + 1;
    // Past the last quad the strip meets its start upside down.
    const int32_t next_top = i + 1 < n ? 2 * i + 2 : 1, next_bottom = i + 1 < n ? 2 * i + 3 : 0;
    AddTriangle(&raw, {top, bottom, next_bottom});
    AddTriangle(&raw, {top, next_bottom, next_top});
  }
  return raw;
}

// Two flat square sheets, [-1, 1]^2 in the planes y = 0 (sheet A) and x = 0
// (sheet B), each a (2n+1) x (2n+1) grid of right triangles, crossing along
// the z axis and sharing only the vertices a = 0 (the origin) and b = 1
// (0, 0, 1/n): edge (a, b) has four faces, two a->b and two b->a, in the
// angular order a->b, a->b, b->a, b->a round it (sheet B turned by
// `flip_second` gives a->b, b->a, b->a, a->b). Elsewhere on the axis each
// sheet has vertices of its own at the same positions. A scan that passes
// through itself looks like this. Faces of sheet A come first.
inline RawMesh TwoSheetsCrossingAlongAnEdge(int n, bool flip_second = false) {
  RawMesh raw;
  raw.name = "crossing sheets";
  AddVertex(&raw, Vec3(0, 0, 0));
  AddVertex(&raw, Vec3(0, 0, 1.0 / n));
  for (int sheet = 0; sheet < 2; ++sheet) {
    const Vec3 across = sheet == 0 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    std::vector<std::vector<int32_t>> id(2 * n + 1, std::vector<int32_t>(2 * n + 1));
    for (int i = -n; i <= n; ++i) {
      for (int j = -n; j <= n; ++j) {
        const bool shared = i == 0 && (j == 0 || j == 1);
        id[i + n][j + n] = shared ? j
                                  : AddVertex(&raw, (static_cast<double>(i) / n) * across +
                                                        Vec3(0, 0, static_cast<double>(j) / n));
      }
    }
    const bool flip = sheet == 1 && flip_second;
    for (int i = 0; i < 2 * n; ++i) {
      for (int j = 0; j < 2 * n; ++j) {
        // Counter-clockwise seen from +y (sheet A) or -x (sheet B): the face
        // on the +across side of the axis runs up it (a -> b).
        const int32_t p00 = id[i][j], p10 = id[i + 1][j], p01 = id[i][j + 1],
                      p11 = id[i + 1][j + 1];
        AddTriangle(&raw, flip ? Triangle{p00, p10, p11} : Triangle{p00, p11, p10});
        AddTriangle(&raw, flip ? Triangle{p00, p11, p01} : Triangle{p00, p01, p11});
      }
    }
  }
  return raw;
}

// A flat n x n grid of the unit square whose face `face` is split along its
// first edge (a, c) at the edge's midpoint b, with the zero-area triangle
// (a, c, b) between it and its neighbour across that edge: the new
// triangles are appended (the split face keeps its id as (a, b, d)). Returns
// the id of the zero-area face. Distances on it stay Euclidean.
inline int32_t AddZeroAreaFace(RawMesh* raw, int32_t face) {
  const Triangle t = raw->triangles[face];
  const int32_t a = t[0], c = t[1], d = t[2];
  const int32_t b = AddVertex(raw, (raw->positions[a] + raw->positions[c]) / 2);
  raw->triangles[face] = {a, b, d};
  AddTriangle(raw, {b, c, d});
  AddTriangle(raw, {a, c, b});
  return static_cast<int32_t>(raw->triangles.size() - 1);
}

// Decimation by vertex clustering (Rossignac & Borrel 1993), the way scans
// are often thinned: every vertex moves to the mean of the vertices in its
// cube of a grid of `cell` (in the mesh's units), and triangles left with a
// repeated corner are dropped. Where the surface is thinner than a cube,
// its sides merge: non-manifold edges and vertices, duplicate faces, and
// handles and tunnels of about the cube's size, as decimated scans have.
inline RawMesh ClusterVertices(const RawMesh& raw, double cell) {
  Vec3 lo = raw.positions.front();
  for (const Vec3& p : raw.positions) lo = lo.cwiseMin(p);
  std::map<std::array<int64_t, 3>, int32_t> cluster;
  std::vector<Vec3> sum;
  std::vector<int32_t> count, id(raw.positions.size());
  for (size_t v = 0; v < raw.positions.size(); ++v) {
    const Vec3 q = (raw.positions[v] - lo) / cell;
    const std::array<int64_t, 3> key = {static_cast<int64_t>(std::floor(q.x())),
                                        static_cast<int64_t>(std::floor(q.y())),
                                        static_cast<int64_t>(std::floor(q.z()))};
    const auto [it, inserted] = cluster.try_emplace(key, static_cast<int32_t>(sum.size()));
    if (inserted) {
      sum.push_back(Vec3::Zero());
      count.push_back(0);
    }
    id[v] = it->second;
    sum[id[v]] += raw.positions[v];
    ++count[id[v]];
  }
  RawMesh out;
  out.name = raw.name + " (clustered)";
  std::vector<int32_t> renumber(sum.size(), kNone);
  for (const Triangle& t : raw.triangles) {
    const Triangle c = {id[t[0]], id[t[1]], id[t[2]]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    Triangle kept;
    for (int i = 0; i < 3; ++i) {
      if (renumber[c[i]] == kNone) {
        renumber[c[i]] = static_cast<int32_t>(out.positions.size());
        out.positions.push_back(sum[c[i]] / count[c[i]]);
      }
      kept[i] = renumber[c[i]];
    }
    AddTriangle(&out, kept);
  }
  return out;
}

// Two spheres (icospheres of `subdivisions`, radius 1) touching at one
// vertex, which both share: a pinched vertex with two fans.
inline RawMesh TwoSpheresTouchingAtAVertex(int subdivisions) {
  const Mesh sphere = gen::Sphere(subdivisions, 1.0);
  RawMesh raw = RawOf(sphere, "two spheres touching");
  // Vertex 0 of the icosphere lies at (-1, t, 0) / |.|: the second sphere is
  // the first mirrored through that point, sharing it.
  const Vec3 touch = sphere.position(0);
  const int32_t n = sphere.num_vertices();
  for (int32_t v = 0; v < n; ++v) raw.positions.push_back(2 * touch - sphere.position(v));
  for (const Triangle& t : sphere.faces()) {
    Triangle u;
    for (int i = 0; i < 3; ++i) u[i] = t[i] == 0 ? 0 : t[i] + n;
    // A point reflection turns faces inside out: turn them back.
    AddTriangle(&raw, {u[0], u[2], u[1]});
  }
  return raw;
}

// `count` small closed spheres (icospheres of one subdivision, radius 0.05)
// in a row beside a unit sphere of `subdivisions`: many tiny components.
inline RawMesh ManyTinyComponents(int count, int subdivisions) {
  RawMesh raw = RawOf(gen::Sphere(subdivisions, 1.0), "many tiny components");
  const Mesh tiny = gen::Sphere(1, 0.05);
  for (int k = 0; k < count; ++k) {
    const int32_t base = static_cast<int32_t>(raw.positions.size());
    const Vec3 at(1.5 + 0.2 * (k % 10), 0.2 * (k / 10), 0);
    for (const Vec3& p : tiny.positions()) raw.positions.push_back(p + at);
    for (const Triangle& t : tiny.faces())
      AddTriangle(&raw, {t[0] + base, t[1] + base, t[2] + base});
  }
  return raw;
}

// `raw` with every `every`-th triangle repeated (a duplicate face, corners
// turned round once) and every `every`-th after the first split by a
// zero-area face (AddZeroAreaFace).
inline RawMesh WithDuplicateAndZeroAreaFaces(RawMesh raw, int every) {
  const int32_t nf = static_cast<int32_t>(raw.triangles.size());
  for (int32_t f = 0; f < nf; f += every) {
    const Triangle t = raw.triangles[f];
    AddTriangle(&raw, {t[1], t[2], t[0]});
  }
  for (int32_t f = every / 2; f < nf; f += every) AddZeroAreaFace(&raw, f);
  return raw;
}

}  // namespace geodex::mesh::testing
