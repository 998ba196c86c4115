// Property test of mesh repair (mesh_repair.h): generated broken meshes of
// every kind (random soups glued along random edges in random orientations,
// books of any number of pages, sheets crossing along edges, fans meeting at
// a vertex, duplicates, flipped faces, and all of them mixed) are repaired
// into a valid mesh of the input's faces, the same one every time, or
// refused for one of the documented reasons (mesh_repair_testing.h checks
// both from the outside).

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/mesh/broken_meshes_testing.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_repair.h"
#include "core/mesh/mesh_repair_testing.h"
#include "gtest/gtest.h"

namespace geodex::mesh {
namespace {

using testing::AddTriangle;
using testing::AddVertex;
using testing::CheckRepair;
using testing::RawOf;
using testing::SameRepair;

// Outcome counts over a family of generated inputs.
struct Tally {
  int repaired = 0;
  int refused = 0;
  int nonmanifold_edges = 0;
  int nonmanifold_vertices = 0;
  int duplicates = 0;
  int reoriented = 0;
};

// Repairs `raw` twice and checks both results; returns false (after adding
// a failure naming `what`) when a check fails.
bool RepairAndCheck(const RawMesh& raw, const std::string& what, Tally* tally) {
  const absl::StatusOr<RepairedMesh> a = RepairMesh(raw);
  const std::string problem = CheckRepair(raw, a);
  if (!problem.empty()) {
    ADD_FAILURE() << what << ": " << problem;
    return false;
  }
  const absl::StatusOr<RepairedMesh> b = RepairMesh(raw);
  if (a.ok() != b.ok() || (a.ok() && !SameRepair(*a, *b)) ||
      (!a.ok() && a.status() != b.status())) {
    ADD_FAILURE() << what << ": two repairs of one input differ";
    return false;
  }
  if (a.ok()) {
    ++tally->repaired;
    tally->nonmanifold_edges += a->report.nonmanifold_edges > 0 ? 1 : 0;
    tally->nonmanifold_vertices += a->report.nonmanifold_vertices > 0 ? 1 : 0;
    tally->duplicates += a->report.duplicate_faces > 0 ? 1 : 0;
    tally->reoriented += a->report.reoriented_faces > 0 ? 1 : 0;
  } else {
    ++tally->refused;
  }
  return true;
}

// A random soup: triangles over a few vertices, most glued to an edge of an
// earlier triangle in a random direction, so that edges get any number of
// faces in any orientation mix. On a coarse grid of positions (half of the
// soups) vertices coincide, faces are coplanar, collinear or of zero area
// and angles round an edge tie.
RawMesh RandomSoup(std::mt19937_64& rng) {
  RawMesh raw;
  raw.name = "soup";
  const int nv = std::uniform_int_distribution<int>(3, 14)(rng);
  const bool grid = rng() % 2 == 0;
  std::uniform_real_distribution<double> coordinate(-1, 1);
  std::uniform_int_distribution<int> cell(0, 2);
  for (int v = 0; v < nv; ++v) {
    AddVertex(&raw, grid ? Vec3(cell(rng), cell(rng), cell(rng))
                         : Vec3(coordinate(rng), coordinate(rng), coordinate(rng)));
  }
  const int nt = std::uniform_int_distribution<int>(1, 36)(rng);
  std::uniform_int_distribution<int> vertex(0, nv - 1);
  for (int t = 0; t < nt; ++t) {
    int32_t a, b;
    if (!raw.triangles.empty() && rng() % 10 < 8) {
      const Triangle& glued =
          raw.triangles[std::uniform_int_distribution<size_t>(0, raw.triangles.size() - 1)(rng)];
      const int i = static_cast<int>(rng() % 3);
      a = glued[i];
      b = glued[(i + 1) % 3];
      if (rng() % 2 == 0) std::swap(a, b);
    } else {
      a = vertex(rng);
      do b = vertex(rng);
      while (b == a);
    }
    int32_t c;
    do c = vertex(rng);
    while (c == a || c == b);
    AddTriangle(&raw, {a, b, c});
  }
  return raw;
}

// A book: `pages` triangles (or two-triangle pages) round the spine from
// vertex 0 to vertex 1 at random angles, each in a random direction.
RawMesh RandomBook(std::mt19937_64& rng) {
  RawMesh raw;
  raw.name = "book";
  AddVertex(&raw, Vec3(0, 0, 0));
  AddVertex(&raw, Vec3(0, 0, 1));
  const int pages = std::uniform_int_distribution<int>(3, 8)(rng);
  std::uniform_real_distribution<double> angle(0, 2 * std::numbers::pi);
  for (int k = 0; k < pages; ++k) {
    const double a = angle(rng);
    const Vec3 out(std::cos(a), std::sin(a), 0);
    const int32_t p = AddVertex(&raw, out + Vec3(0, 0, 0.5));
    if (rng() % 2 == 0) {
      AddTriangle(&raw, rng() % 2 == 0 ? Triangle{0, 1, p} : Triangle{1, 0, p});
    } else {
      const int32_t q = AddVertex(&raw, out + Vec3(0, 0, 1.5));
      const bool forward = rng() % 2 == 0;
      AddTriangle(&raw, forward ? Triangle{0, p, 1} : Triangle{1, p, 0});
      AddTriangle(&raw, forward ? Triangle{1, p, q} : Triangle{q, p, 1});
    }
  }
  return raw;
}

// `sheets` flat n x n grids through the z axis at random angles, all holding
// the axis's vertices (ids 0..n-1), each oriented at random: every axis edge
// is shared by 2 * sheets faces, two per sheet, crossing.
RawMesh CrossingSheets(std::mt19937_64& rng, int sheets, int n) {
  RawMesh raw;
  raw.name = "crossing sheets";
  for (int j = 0; j < n; ++j) AddVertex(&raw, Vec3(0, 0, j));
  std::uniform_real_distribution<double> angle(0, std::numbers::pi);
  for (int s = 0; s < sheets; ++s) {
    const double a = angle(rng);
    const Vec3 across(std::cos(a), std::sin(a), 0);
    // Columns i = -n/2 .. n/2 across the axis; column 0 is the axis.
    const int half = n / 2;
    std::vector<std::vector<int32_t>> id(2 * half + 1, std::vector<int32_t>(n));
    for (int i = -half; i <= half; ++i) {
      for (int j = 0; j < n; ++j) {
        id[i + half][j] = i == 0 ? j : AddVertex(&raw, i * across + Vec3(0, 0, j));
      }
    }
    const bool flip = rng() % 2 == 0;
    for (int i = 0; i < 2 * half; ++i) {
      for (int j = 0; j + 1 < n; ++j) {
        const int32_t a00 = id[i][j], a10 = id[i + 1][j], a01 = id[i][j + 1],
                      a11 = id[i + 1][j + 1];
        AddTriangle(&raw, flip ? Triangle{a00, a11, a10} : Triangle{a00, a10, a11});
        AddTriangle(&raw, flip ? Triangle{a00, a01, a11} : Triangle{a00, a11, a01});
      }
    }
  }
  return raw;
}

// `fans` cones (closed or open) sharing their apex, vertex 0.
RawMesh FansAtAVertex(std::mt19937_64& rng) {
  RawMesh raw;
  raw.name = "fans";
  AddVertex(&raw, Vec3(0, 0, 0));
  const int fans = std::uniform_int_distribution<int>(2, 5)(rng);
  for (int f = 0; f < fans; ++f) {
    const int sides = std::uniform_int_distribution<int>(3, 6)(rng);
    const bool closed = rng() % 2 == 0;
    const Vec3 axis = Vec3(std::cos(f), std::sin(f), (f % 2 == 0) ? 1 : -1).normalized();
    const Vec3 u = axis.unitOrthogonal(), w = axis.cross(u);
    const int32_t first = static_cast<int32_t>(raw.positions.size());
    for (int k = 0; k < sides; ++k) {
      const double t = 2 * std::numbers::pi * k / sides;
      AddVertex(&raw, axis + 0.4 * (std::cos(t) * u + std::sin(t) * w));
    }
    for (int k = 0; k + (closed ? 0 : 1) < sides; ++k) {
      AddTriangle(&raw, {0, first + k, first + (k + 1) % sides});
    }
  }
  return raw;
}

// Breaks a mesh further: flips some faces, appends duplicates (in any
// corner order) and extra faces glued to random edges.
void Break(std::mt19937_64& rng, RawMesh* raw) {
  const int nf = static_cast<int>(raw->triangles.size());
  for (int k = std::uniform_int_distribution<int>(0, 3)(rng); k > 0; --k) {
    Triangle& t = raw->triangles[rng() % nf];
    std::swap(t[1], t[2]);
  }
  for (int k = std::uniform_int_distribution<int>(0, 3)(rng); k > 0; --k) {
    Triangle t = raw->triangles[rng() % nf];
    std::rotate(t.begin(), t.begin() + rng() % 3, t.end());
    if (rng() % 2 == 0) std::swap(t[1], t[2]);
    AddTriangle(raw, t);
  }
  for (int k = std::uniform_int_distribution<int>(0, 4)(rng); k > 0; --k) {
    const Triangle& glued = raw->triangles[rng() % nf];
    const int i = static_cast<int>(rng() % 3);
    int32_t a = glued[i], b = glued[(i + 1) % 3];
    if (rng() % 2 == 0) std::swap(a, b);
    const Vec3 at = (raw->positions[a] + raw->positions[b]) / 2 +
                    Vec3(std::uniform_real_distribution<double>(-1, 1)(rng), 0.3, -0.2);
    AddTriangle(raw, {a, b, AddVertex(raw, at)});
  }
}

TEST(MeshRepairPropertyTest, RandomSoupsAreRepairedOrRefusedForAReason) {
  std::mt19937_64 rng(20240601);
  Tally tally;
  for (int i = 0; i < 12000; ++i) {
    if (!RepairAndCheck(RandomSoup(rng), absl::StrCat("soup ", i), &tally)) break;
  }
  std::printf(
      "random soups: %d repaired (%d with non-manifold edges, %d with non-manifold "
      "vertices, %d with duplicates, %d re-oriented), %d refused as not orientable\n",
      tally.repaired, tally.nonmanifold_edges, tally.nonmanifold_vertices, tally.duplicates,
      tally.reoriented, tally.refused);
  // The generator reaches every repair, and most soups are repaired.
  EXPECT_GT(tally.nonmanifold_edges, 1000);
  EXPECT_GT(tally.nonmanifold_vertices, 1000);
  EXPECT_GT(tally.duplicates, 1000);
  EXPECT_GT(tally.reoriented, 1000);
  EXPECT_GT(tally.repaired, tally.refused);
}

TEST(MeshRepairPropertyTest, BooksSheetsAndFansAreRepaired) {
  std::mt19937_64 rng(7);
  Tally tally;
  for (int i = 0; i < 600; ++i) {
    RawMesh raw = i % 3 == 0   ? RandomBook(rng)
                  : i % 3 == 1 ? CrossingSheets(rng, 2 + i % 4, 3 + i % 3)
                               : FansAtAVertex(rng);
    const std::string what = absl::StrCat(raw.name, " ", i);
    if (!RepairAndCheck(raw, what, &tally)) break;
    // Nothing here is a Möbius strip: every one is repaired.
    EXPECT_EQ(tally.refused, 0) << what;
  }
  EXPECT_EQ(tally.repaired, 600);
}

TEST(MeshRepairPropertyTest, BrokenClosedMeshesAreRepairedOrRefusedForAReason) {
  std::mt19937_64 rng(11);
  Tally tally;
  for (int i = 0; i < 600; ++i) {
    RawMesh raw = i % 4 == 0   ? RawOf(gen::Sphere(1, 1.0), "sphere")
                  : i % 4 == 1 ? testing::TwoCubesSharingAnEdge()
                  : i % 4 == 2 ? CrossingSheets(rng, 2, 4)
                               : testing::TwoPyramidsApexToApex();
    Break(rng, &raw);
    if (!RepairAndCheck(raw, absl::StrCat(raw.name, " broken ", i), &tally)) break;
  }
  EXPECT_GT(tally.repaired, 500);
}

TEST(MeshRepairPropertyTest, MobiusStripsAreRefusedUnlessCutOpen) {
  std::mt19937_64 rng(3);
  Tally tally;
  for (int n = 6; n < 40; ++n) {
    ASSERT_TRUE(RepairAndCheck(testing::MobiusStrip(n), "mobius", &tally));
    EXPECT_EQ(tally.refused, n - 5);
  }
  // A third face on one of its edges cuts the strip there: then it is a
  // twisted band with a slit, orientable, and repaired.
  RawMesh slit = testing::MobiusStrip(24);
  const Triangle t = slit.triangles[5];
  AddTriangle(&slit, {t[0], t[1], AddVertex(&slit, Vec3(0, 0, 5))});
  const absl::StatusOr<RepairedMesh> r = RepairMesh(slit);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(CheckRepair(slit, r), "");
  EXPECT_EQ(r->report.nonmanifold_edges, 1);
}

}  // namespace
}  // namespace geodex::mesh
