#include "core/mesh/mesh_repair.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <span>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/edge_groups.h"
#include "core/common/status_macros.h"

namespace geodex::mesh {
namespace {

// Doubled area under this fraction of the longest squared edge, but not
// zero: a sliver (angles under about 1e-6 rad), counted in the report.
constexpr double kSliverAreaRatio = 1e-6;

// Same wording as CreateLoadedMesh, so that strict and repairing loads
// explain face ids alike.
absl::Status Refuse(const RawMesh& raw, std::string message) {
  if (raw.polygons) {
    absl::StrAppend(&message,
                    " [face ids count triangles after fan triangulation of the file's polygons]");
  }
  return absl::InvalidArgumentError(message);
}

// Union-find whose root is the smallest member, so that a set is named by
// its first element in id order (the order the repair numbers fans in).
class DisjointSets {
 public:
  explicit DisjointSets(int32_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int32_t Find(int32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void Union(int32_t a, int32_t b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<int32_t> parent_;
};

std::string Count(int32_t n, const char* one, const char* many) {
  return absl::StrCat(n, " ", n == 1 ? one : many);
}

// The soup being repaired: the kept triangles in input orientation, and
// their half-edges 3k+i from corner i to corner i+1 of kept triangle k.
struct Soup {
  const RawMesh* raw;
  std::vector<int32_t> kept;  // kept triangle k -> input triangle

  const Triangle& tri(int32_t k) const { return raw->triangles[kept[k]]; }
  int32_t Origin(int32_t h) const { return tri(h / 3)[h % 3]; }
  int32_t Dest(int32_t h) const { return tri(h / 3)[(h % 3 + 1) % 3]; }
  int32_t Opposite(int32_t h) const { return tri(h / 3)[(h % 3 + 2) % 3]; }
};

// Pairs the half-edges of one non-manifold edge (a, b), a < b, in *mate,
// with the faces oriented as `flip` says. Ordered by angle round a->b, a
// face that runs b->a followed counter-clockwise by one that runs a->b
// encloses, with their orientations, the inside of a solid between them (a
// face's normal points counter-clockwise round a->b when it runs a->b): they
// are one sheet. Both directions follow the orientation, so every pair made
// agrees with `flip`.
void PairRoundEdge(const Soup& soup, std::span<const int32_t> halfedges,
                   const std::vector<uint8_t>& flip, std::vector<int32_t>* mate) {
  const auto& positions = soup.raw->positions;
  const int32_t a = std::min(soup.Origin(halfedges[0]), soup.Dest(halfedges[0]));
  const int32_t b = std::max(soup.Origin(halfedges[0]), soup.Dest(halfedges[0]));
  const Vec3 e = positions[b] - positions[a];
  const int n = static_cast<int>(halfedges.size());
  if (!(e.norm() > 0)) return;  // no direction to order the faces round
  const Vec3 axis = e.normalized();
  std::vector<Vec3> across(n);  // the face's direction away from the edge
  Vec3 x = Vec3::Zero();
  for (int i = 0; i < n; ++i) {
    const Vec3 u = positions[soup.Opposite(halfedges[i])] - positions[a];
    across[i] = u - u.dot(axis) * axis;
    if (x.isZero() && across[i].norm() > 0) x = across[i].normalized();
  }
  const Vec3 y = axis.cross(x);
  std::vector<std::pair<double, int32_t>> order(n);
  for (int i = 0; i < n; ++i) {
    double angle = std::atan2(across[i].dot(y), across[i].dot(x));
    if (angle < 0) angle += 2 * std::numbers::pi;
    order[i] = {angle, halfedges[i]};
  }
  std::sort(order.begin(), order.end());
  auto runs_from = [&](int32_t h) { return flip[h / 3] ? soup.Dest(h) : soup.Origin(h); };
  for (int i = 0; i < n; ++i) {
    const int32_t h = order[i].second, g = order[(i + 1) % n].second;
    if ((*mate)[h] != kNone || (*mate)[g] != kNone || h == g) continue;
    if (runs_from(h) == b && runs_from(g) == a) {
      (*mate)[h] = g;
      (*mate)[g] = h;
    }
  }
}

// The corner of kept triangle k at input vertex v (one of its corners).
int CornerAt(const Soup& soup, int32_t k, int32_t v) {
  const Triangle& t = soup.tri(k);
  return t[0] == v ? 0 : t[1] == v ? 1 : 2;
}

// The fans of the kept triangles' corners (corner 3k+c: corner c of kept
// triangle k, input order): two corners at one vertex are in one fan when a
// chain of paired edges round the vertex joins them.
DisjointSets Fans(const Soup& soup, const std::vector<int32_t>& mate) {
  const int32_t nh = static_cast<int32_t>(mate.size());
  DisjointSets fans(nh);
  for (int32_t h = 0; h < nh; ++h) {
    const int32_t g = mate[h];
    if (g == kNone || g < h) continue;
    const int32_t kh = h / 3, kg = g / 3;
    fans.Union(h, 3 * kg + CornerAt(soup, kg, soup.Origin(h)));
    fans.Union(3 * kh + (h % 3 + 1) % 3, 3 * kg + CornerAt(soup, kg, soup.Dest(h)));
  }
  return fans;
}

// The half-edges in order of the two fans they join (their vertices once
// split), with the bounds of each run of one pair of fans.
struct FanEdges {
  std::vector<int32_t> order;
  std::vector<int32_t> run_begin;  // runs [run_begin[r], run_begin[r + 1])
};

FanEdges GroupByFans(const std::vector<int32_t>& mate, DisjointSets& fans) {
  const int32_t nh = static_cast<int32_t>(mate.size());
  std::vector<std::pair<int64_t, int32_t>> keyed(nh);
  for (int32_t h = 0; h < nh; ++h) {
    const int64_t u = fans.Find(h), w = fans.Find(h - h % 3 + (h % 3 + 1) % 3);
    keyed[h] = {std::min(u, w) * nh + std::max(u, w), h};
  }
  std::sort(keyed.begin(), keyed.end());
  FanEdges out;
  out.order.resize(nh);
  for (int32_t i = 0; i < nh; ++i) {
    out.order[i] = keyed[i].second;
    if (i == 0 || keyed[i].first != keyed[i - 1].first) out.run_begin.push_back(i);
  }
  out.run_begin.push_back(nh);
  return out;
}

// Makes every copy of an edge join its own two vertices once vertices are
// split by fans. The pairing round non-manifold edges can leave two copies
// whose faces still meet round both ends (two sheets crossing along the edge,
// paired across the sheets): the edge would join the same two vertices
// twice. Such copies are undone; then two unpaired half-edges that join the
// same two fans are the two ends of those fans (a fan has at most two free
// edges) and, the fans being consistently oriented, run in opposite
// directions: they are paired, which closes both fans and changes no vertex.
// Cuts only split fans, so one round of cuts and one of pairings is enough.
void SeparateCopies(const Soup& soup, const std::vector<uint8_t>& flip,
                    std::vector<int32_t>* mate) {
  std::vector<int32_t>& m = *mate;
  DisjointSets fans = Fans(soup, m);
  FanEdges runs = GroupByFans(m, fans);
  bool cut = false;
  for (size_t r = 0; r + 1 < runs.run_begin.size(); ++r) {
    const int32_t begin = runs.run_begin[r], end = runs.run_begin[r + 1];
    if (end - begin <= 2) continue;
    for (int32_t i = begin; i < end; ++i) {
      const int32_t h = runs.order[i];
      if (m[h] == kNone) continue;
      m[m[h]] = kNone;
      m[h] = kNone;
      cut = true;
    }
  }
  if (cut) {
    fans = Fans(soup, m);
    runs = GroupByFans(m, fans);
  }
  auto runs_from = [&](int32_t h) { return flip[h / 3] ? soup.Dest(h) : soup.Origin(h); };
  for (size_t r = 0; r + 1 < runs.run_begin.size(); ++r) {
    const int32_t begin = runs.run_begin[r], end = runs.run_begin[r + 1];
    if (end - begin != 2) continue;
    const int32_t h = runs.order[begin], g = runs.order[begin + 1];
    if (m[h] != kNone || m[g] != kNone || runs_from(h) == runs_from(g)) continue;
    m[h] = g;
    m[g] = h;
  }
}

// Checks what cannot be repaired, as Mesh::Create does and with its
// messages, and counts zero-area and sliver faces.
absl::Status CheckUnrepairable(const RawMesh& raw, RepairReport* report) {
  const std::string& name = raw.name;
  if (raw.triangles.empty()) return Refuse(raw, absl::StrCat(name, ": mesh has no faces"));
  if (raw.positions.size() >= static_cast<size_t>(INT32_MAX) ||
      raw.triangles.size() >= INT32_MAX / 3) {
    return Refuse(raw, absl::StrCat(name, ": mesh too large"));
  }
  for (size_t v = 0; v < raw.positions.size(); ++v) {
    const Vec3& p = raw.positions[v];
    if (!p.allFinite()) {
      return Refuse(raw, absl::StrFormat("%s: vertex %d has a non-finite coordinate (%g, %g, %g)",
                                         name, v, p.x(), p.y(), p.z()));
    }
  }
  const int64_t n = static_cast<int64_t>(raw.positions.size());
  // A file polygon with a repeated corner can fan into triangles that do
  // not repeat one (0 1 2 1 gives 0 1 2 and 0 2 1, duplicates the repair
  // would drop): such a polygon is refused whole. Its corners are its first
  // triangle's, then the last corner of each next one.
  if (raw.polygons && raw.input_face.size() == raw.triangles.size()) {
    std::vector<int32_t> corners;
    for (size_t first = 0, end; first < raw.triangles.size(); first = end) {
      end = first + 1;
      while (end < raw.triangles.size() && raw.input_face[end] == raw.input_face[first]) ++end;
      if (end - first == 1) continue;
      corners.assign(raw.triangles[first].begin(), raw.triangles[first].end());
      for (size_t t = first + 1; t < end; ++t) corners.push_back(raw.triangles[t][2]);
      std::sort(corners.begin(), corners.end());
      const auto repeated = std::adjacent_find(corners.begin(), corners.end());
      if (repeated != corners.end()) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s: polygon %d of the file (%d corners) repeats vertex %d", name,
                            raw.input_face[first], corners.size(), *repeated));
      }
    }
  }
  for (size_t f = 0; f < raw.triangles.size(); ++f) {
    const Triangle& t = raw.triangles[f];
    for (int i = 0; i < 3; ++i) {
      if (t[i] < 0 || t[i] >= n) {
        return Refuse(raw, absl::StrFormat("%s: face %d references vertex %d, out of range [0, %d)",
                                           name, f, t[i], n));
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      return Refuse(raw, absl::StrFormat("%s: face %d repeats a vertex (%d %d %d)", name, f, t[0],
                                         t[1], t[2]));
    }
    const Vec3 &a = raw.positions[t[0]], &b = raw.positions[t[1]], &c = raw.positions[t[2]];
    if (IsZeroAreaTriangle(a, b, c)) {
      ++report->zero_area_faces;
    } else {
      const double longest2 =
          std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
      if ((b - a).cross(c - a).norm() < kSliverAreaRatio * longest2) ++report->sliver_faces;
    }
  }
  return absl::OkStatus();
}

// Drops duplicate triangles. Fills soup->kept and, per input triangle, the
// kept triangle of its group (itself when kept).
void DropDuplicates(const RawMesh& raw, Soup* soup, std::vector<int32_t>* group_keeper,
                    RepairReport* report) {
  const int32_t nf = static_cast<int32_t>(raw.triangles.size());
  std::vector<std::pair<Triangle, int32_t>> sorted(nf);
  for (int32_t f = 0; f < nf; ++f) {
    Triangle t = raw.triangles[f];
    std::sort(t.begin(), t.end());
    sorted[f] = {t, f};
  }
  std::sort(sorted.begin(), sorted.end());
  group_keeper->assign(nf, kNone);
  for (int32_t i = 0; i < nf; ++i) {
    const bool first = i == 0 || sorted[i].first != sorted[i - 1].first;
    (*group_keeper)[sorted[i].second] =
        first ? sorted[i].second : (*group_keeper)[sorted[i - 1].second];
  }
  for (int32_t f = 0; f < nf; ++f) {
    if ((*group_keeper)[f] == f) {
      soup->kept.push_back(f);
    } else {
      ++report->duplicate_faces;
    }
  }
}

// Pairs the half-edges of the kept triangles on edges of exactly two faces
// (mate[h], kNone otherwise) and lists the half-edges of each non-manifold
// edge (more than two faces) in *nonmanifold.
std::vector<int32_t> PairManifoldEdges(const Soup& soup,
                                       std::vector<std::vector<int32_t>>* nonmanifold) {
  const int32_t nh = 3 * static_cast<int32_t>(soup.kept.size());
  auto ends = [&](int32_t h) { return std::pair<int32_t, int32_t>(soup.Origin(h), soup.Dest(h)); };
  std::vector<int32_t> mate(nh, kNone);
  // The visit never fails.
  ForEachEdge(nh, ends, [&](std::span<const int32_t> group, int64_t, int64_t) {
    if (group.size() == 2) {
      mate[group[0]] = group[1];
      mate[group[1]] = group[0];
    } else if (group.size() > 2) {
      nonmanifold->emplace_back(group.begin(), group.end());
    }
    return absl::OkStatus();
  }).IgnoreError();
  return mate;
}

// Chooses which kept triangles to flip so that paired half-edges run in
// opposite directions, keeping in each connected part the orientation most
// of its faces have (the lowest face's on a tie). Errors: InvalidArgument
// when no orientation agrees across every paired edge.
absl::StatusOr<std::vector<uint8_t>> Orient(const Soup& soup, const std::vector<int32_t>& mate) {
  const int32_t nk = static_cast<int32_t>(soup.kept.size());
  std::vector<int8_t> flip(nk, -1);
  std::vector<int32_t> part;
  for (int32_t root = 0; root < nk; ++root) {
    if (flip[root] >= 0) continue;
    part.assign(1, root);
    flip[root] = 0;
    for (size_t next = 0; next < part.size(); ++next) {
      const int32_t k = part[next];
      for (int i = 0; i < 3; ++i) {
        const int32_t h = 3 * k + i, g = mate[h];
        if (g == kNone) continue;
        const int32_t other = g / 3;
        const int8_t want = flip[k] ^ (soup.Origin(h) == soup.Origin(g) ? 1 : 0);
        if (flip[other] < 0) {
          flip[other] = want;
          part.push_back(other);
        } else if (flip[other] != want) {
          return Refuse(*soup.raw,
                        absl::StrFormat("%s: the surface is not orientable: faces %d and %d meet "
                                        "on edge (%d, %d), and no orientation of the faces agrees "
                                        "across every edge (a Möbius strip, for one)",
                                        soup.raw->name, soup.kept[k], soup.kept[other],
                                        soup.Origin(h), soup.Dest(h)));
        }
      }
    }
    int32_t flipped = 0;
    for (int32_t k : part) flipped += flip[k];
    if (2 * flipped > static_cast<int32_t>(part.size())) {
      for (int32_t k : part) flip[k] ^= 1;
    }
  }
  return std::vector<uint8_t>(flip.begin(), flip.end());
}

}  // namespace

std::string RepairReport::Summary() const {
  std::string out =
      absl::StrCat(Count(nonmanifold_vertices, "non-manifold vertex", "non-manifold vertices"),
                   " split (", Count(vertex_copies, "copy", "copies"), "), ",
                   Count(nonmanifold_edges, "non-manifold edge", "non-manifold edges"), " cut (",
                   Count(edge_copies, "copy", "copies"), "), ",
                   Count(duplicate_faces, "duplicate face", "duplicate faces"), " dropped, ",
                   Count(reoriented_faces, "face", "faces"), " re-oriented, ",
                   Count(unreferenced_vertices, "unreferenced vertex", "unreferenced vertices"),
                   " ignored, ", Count(zero_area_faces, "zero-area face", "zero-area faces"),
                   " and ", Count(sliver_faces, "sliver", "slivers"), " kept");
  if (weld.welded) {
    absl::StrAppend(&out, "; ", weld.welded_corners,
                    weld.welded_corners == 1 ? " corner welded" : " corners welded");
  }
  return out;
}

std::string RepairReport::ToText() const {
  std::string out = absl::StrFormat(
      "mesh_repairs = %s\nmesh_nonmanifold_vertices_split = %d\nmesh_nonmanifold_vertex_copies = "
      "%d\nmesh_nonmanifold_edges_cut = %d\nmesh_nonmanifold_edge_copies = %d\n"
      "mesh_duplicate_faces_dropped = %d\nmesh_faces_reoriented = %d\n"
      "mesh_unreferenced_vertices = %d\nmesh_zero_area_faces = %d\nmesh_sliver_faces = %d\n",
      Summary(), nonmanifold_vertices, vertex_copies, nonmanifold_edges, edge_copies,
      duplicate_faces, reoriented_faces, unreferenced_vertices, zero_area_faces, sliver_faces);
  if (weld.welded) {
    absl::StrAppendFormat(&out,
                          "mesh_welded_corners = %d\nmesh_weld_tolerance = %.9g\n"
                          "mesh_degenerate_corners_unwelded = %d\n",
                          weld.welded_corners, weld.tolerance, weld.degenerate_corners);
  }
  return out;
}

namespace {

// The oriented faces. Flipping (a, b, c) to (a, c, b) turns input corner i
// into corner kFlipCorner[i].
constexpr std::array<uint8_t, 3> kSameCorner = {0, 1, 2}, kFlipCorner = {0, 2, 1};

// Input vertices no face of `faces` uses, of `num_input_vertices`.
int32_t CountUnreferenced(int32_t num_input_vertices, const std::vector<Triangle>& faces) {
  std::vector<uint8_t> used(num_input_vertices, 0);
  for (const Triangle& t : faces) {
    for (int32_t v : t) used[v] = 1;
  }
  return static_cast<int32_t>(std::count(used.begin(), used.end(), 0));
}

// The soup's half-edges paired (`mate`, kNone on the boundary) and its
// faces' orientation (`flip`: 1 where a kept face is reversed).
struct OrientedSoup {
  std::vector<int32_t> mate;
  std::vector<uint8_t> flip;
};

absl::StatusOr<OrientedSoup> OrientAndPair(const Soup& soup, RepairReport* report) {
  // Orientation first, from the edges of two faces only: what is refused is
  // a surface not orientable once its non-manifold edges are cut. The pairs
  // made round non-manifold edges then follow that orientation.
  std::vector<std::vector<int32_t>> nonmanifold;
  std::vector<int32_t> mate = PairManifoldEdges(soup, &nonmanifold);
  GEODEX_ASSIGN_OR_RETURN(std::vector<uint8_t> flip, Orient(soup, mate));
  for (const std::vector<int32_t>& halfedges : nonmanifold) {
    PairRoundEdge(soup, halfedges, flip, &mate);
  }
  SeparateCopies(soup, flip, &mate);
  // Parts joined round non-manifold edges keep their majority's orientation.
  absl::StatusOr<std::vector<uint8_t>> final_flip = Orient(soup, mate);
  if (!final_flip.ok()) {
    return absl::InternalError(absl::StrCat("mesh repair paired faces against their orientation: ",
                                            final_flip.status().message()));
  }
  flip = *std::move(final_flip);
  report->nonmanifold_edges = static_cast<int32_t>(nonmanifold.size());
  for (const std::vector<int32_t>& halfedges : nonmanifold) {
    for (int32_t h : halfedges) report->edge_copies += mate[h] == kNone || mate[h] > h ? 1 : 0;
  }
  const int32_t nk = static_cast<int32_t>(soup.kept.size());
  for (int32_t k = 0; k < nk; ++k) report->reoriented_faces += flip[k];
  return OrientedSoup{std::move(mate), std::move(flip)};
}

// The oriented faces, with one vertex per fan; the fan of a vertex's first
// corner (in face order) keeps its id, the others' are copies appended to
// `positions` (and `maps`).
std::vector<Triangle> FacesByFan(const Soup& soup, const OrientedSoup& oriented,
                                 std::vector<Vec3>& positions, RepairMaps& maps,
                                 RepairReport& report) {
  const int32_t nk = static_cast<int32_t>(soup.kept.size());
  std::vector<Triangle> faces(nk);
  DisjointSets fans = Fans(soup, oriented.mate);
  std::vector<int32_t> fan_vertex(3 * nk, kNone);
  std::vector<int32_t> fans_of(maps.num_input_vertices, 0);
  for (int32_t x = 0; x < 3 * nk; ++x) {
    if (fans.Find(x) != x) continue;  // not the first corner of its fan
    const int32_t v = soup.tri(x / 3)[x % 3];
    if (fans_of[v]++ == 0) {
      fan_vertex[x] = v;
    } else {
      fan_vertex[x] = static_cast<int32_t>(positions.size());
      const Vec3 at = positions[v];
      positions.push_back(at);
      maps.vertex_copies.push_back(v);
    }
  }
  for (int32_t x = 0; x < 3 * nk; ++x) {
    const int32_t k = x / 3;
    faces[k][oriented.flip[k] ? kFlipCorner[x % 3] : x % 3] = fan_vertex[fans.Find(x)];
  }
  for (int32_t count : fans_of) {
    if (count > 1) {
      ++report.nonmanifold_vertices;
      report.vertex_copies += count;
    }
  }
  return faces;
}

// Where each input triangle went: its kept face (its keeper's for a
// duplicate) and its corners there.
std::vector<InputFace> InputFaces(const RawMesh& raw, const Soup& soup,
                                  const std::vector<int32_t>& group_keeper,
                                  const std::vector<uint8_t>& flip) {
  const int32_t nk = static_cast<int32_t>(soup.kept.size());
  const int32_t nf = static_cast<int32_t>(raw.triangles.size());
  std::vector<int32_t> internal_of(nf, kNone);
  for (int32_t k = 0; k < nk; ++k) internal_of[soup.kept[k]] = k;
  std::vector<InputFace> faces(nf);
  for (int32_t f = 0; f < nf; ++f) {
    InputFace& out = faces[f];
    const int32_t keeper = group_keeper[f];
    out.face = internal_of[keeper];
    out.dropped = keeper != f;
    out.reoriented = !out.dropped && flip[out.face];
    if (!out.dropped) {
      out.corner = flip[out.face] ? kFlipCorner : kSameCorner;
      continue;
    }
    // The duplicate's corners among its keeper's (the same vertex set).
    const Triangle& kept_corners = raw.triangles[keeper];
    const std::array<uint8_t, 3> kept_to_internal = flip[out.face] ? kFlipCorner : kSameCorner;
    for (int i = 0; i < 3; ++i) {
      const int j = static_cast<int>(
          std::find(kept_corners.begin(), kept_corners.end(), raw.triangles[f][i]) -
          kept_corners.begin());
      out.corner[i] = kept_to_internal[j];
    }
  }
  return faces;
}

}  // namespace

absl::StatusOr<RepairedMesh> RepairMesh(RawMesh raw, const RepairOptions& options) {
  const int32_t num_input_vertices = static_cast<int32_t>(raw.positions.size());
  if (options.strict) {
    const WeldReport weld = raw.weld;
    GEODEX_ASSIGN_OR_RETURN(LoadedMesh loaded, CreateLoadedMesh(std::move(raw)));
    RepairedMesh out = WithoutRepairs(std::move(loaded.mesh));
    out.report.weld = weld;
    return out;
  }
  RepairReport report;
  GEODEX_RETURN_IF_ERROR(CheckUnrepairable(raw, &report));
  report.unreferenced_vertices = CountUnreferenced(num_input_vertices, raw.triangles);

  report.weld = raw.weld;

  Soup soup{&raw, {}};
  std::vector<int32_t> group_keeper;
  DropDuplicates(raw, &soup, &group_keeper, &report);
  GEODEX_ASSIGN_OR_RETURN(const OrientedSoup oriented, OrientAndPair(soup, &report));

  std::vector<Vec3> positions = std::move(raw.positions);
  RepairMaps maps;
  maps.num_input_vertices = num_input_vertices;
  std::vector<Triangle> faces = FacesByFan(soup, oriented, positions, maps, report);
  if (report.duplicate_faces > 0 || report.reoriented_faces > 0) {
    maps.faces = InputFaces(raw, soup, group_keeper, oriented.flip);
  }

  MeshOptions mesh_options;
  mesh_options.allow_zero_area_faces = true;
  absl::StatusOr<Mesh> mesh =
      Mesh::Create(std::move(positions), std::move(faces), raw.name, mesh_options);
  if (!mesh.ok()) {
    // The steps above make a valid mesh of every soup they accept; this is a
    // defect of the repair, not of the input.
    return absl::InternalError(
        absl::StrCat("mesh repair made an invalid mesh: ", mesh.status().message()));
  }
  return RepairedMesh{*std::move(mesh), std::move(maps), report};
}

absl::StatusOr<RepairedMesh> LoadAndRepairMesh(const std::string& path,
                                               const RepairOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(RawMesh raw, LoadRawMeshFile(path, options.read));
  return RepairMesh(std::move(raw), options);
}

RepairedMesh WithoutRepairs(Mesh mesh) {
  RepairedMesh out{std::move(mesh), {}, {}};
  out.maps.num_input_vertices = out.mesh.num_vertices();
  for (int32_t v = 0; v < out.mesh.num_vertices(); ++v) {
    out.report.unreferenced_vertices += out.mesh.IsReferenced(v) ? 0 : 1;
  }
  return out;
}

}  // namespace geodex::mesh
