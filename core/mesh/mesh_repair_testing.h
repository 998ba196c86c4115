#pragma once

// What RepairMesh (core/mesh/mesh_repair.h) promises, checked from the
// outside on any input: the property test (mesh_repair_property_test.cc) and
// the repair fuzz target (tests/fuzz/fuzz_repair.cc) share it. Test-only,
// header-only.
//
// A repaired mesh must be valid (Mesh::Create accepts its arrays), hold the
// input's faces (one internal face per distinct vertex set, in input order,
// each with its input corners' positions), keep every input edge of exactly
// two faces joined, and report what it did consistently. A refusal must be
// InvalidArgument for one of the documented reasons, and a refusal as "not
// orientable" must be true of the surface with its non-manifold edges cut,
// which is recomputed here independently.

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_repair.h"

namespace geodex::mesh::testing {

// Whether the raw mesh's triangles, duplicates dropped and with only the
// edges of exactly two triangles joined, can be oriented consistently: a
// plain breadth-first parity walk, independent of the repair's code.
inline bool OrientableOnceCut(const RawMesh& raw) {
  // Keep the first triangle of each vertex set.
  std::map<std::array<int32_t, 3>, int32_t> first;
  std::vector<int32_t> kept;
  for (int32_t f = 0; f < static_cast<int32_t>(raw.triangles.size()); ++f) {
    std::array<int32_t, 3> key = raw.triangles[f];
    std::sort(key.begin(), key.end());
    if (first.emplace(key, f).second) kept.push_back(f);
  }
  // Half-edges by undirected edge.
  std::map<std::pair<int32_t, int32_t>, std::vector<std::pair<int32_t, bool>>> edges;
  for (int32_t k = 0; k < static_cast<int32_t>(kept.size()); ++k) {
    const Triangle& t = raw.triangles[kept[k]];
    for (int i = 0; i < 3; ++i) {
      const int32_t a = t[i], b = t[(i + 1) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back({k, a < b});
    }
  }
  std::vector<std::vector<std::pair<int32_t, int>>> adjacent(kept.size());  // (other, parity)
  for (const auto& [edge, halves] : edges) {
    if (halves.size() != 2) continue;
    // Same direction: the two must differ in flip.
    const int parity = halves[0].second == halves[1].second ? 1 : 0;
    adjacent[halves[0].first].push_back({halves[1].first, parity});
    adjacent[halves[1].first].push_back({halves[0].first, parity});
  }
  std::vector<int> flip(kept.size(), -1);
  for (size_t root = 0; root < kept.size(); ++root) {
    if (flip[root] >= 0) continue;
    flip[root] = 0;
    std::vector<int32_t> queue = {static_cast<int32_t>(root)};
    while (!queue.empty()) {
      const int32_t k = queue.back();
      queue.pop_back();
      for (const auto& [other, parity] : adjacent[k]) {
        const int want = flip[k] ^ parity;
        if (flip[other] < 0) {
          flip[other] = want;
          queue.push_back(other);
        } else if (flip[other] != want) {
          return false;
        }
      }
    }
  }
  return true;
}

// CheckRepair of a refusal: InvalidArgument for a documented reason, and
// "not orientable" only when the surface is not, once cut.
inline std::string CheckRefusal(const RawMesh& raw, const absl::Status& status) {
  if (status.code() != absl::StatusCode::kInvalidArgument) {
    return absl::StrCat("refused with a code other than InvalidArgument: ", status.ToString());
  }
  const std::string message(status.message());
  for (const char* reason : {"non-finite coordinate", "repeats a vertex", "repeats vertex",
                             "mesh has no faces", "out of range", "mesh too large"}) {
    if (message.find(reason) != std::string::npos) return "";
  }
  if (message.find("not orientable") != std::string::npos) {
    if (OrientableOnceCut(raw)) {
      return absl::StrCat("refused as not orientable, but it is once cut: ", message);
    }
    return "";
  }
  return absl::StrCat("refused for a reason the repair does not list: ", message);
}

// The input vertex that vertex v of the repaired mesh is or copies.
inline int32_t InputVertexOf(const RawMesh& raw, const RepairedMesh& r, int32_t v) {
  const int32_t nv = static_cast<int32_t>(raw.positions.size());
  return v < nv ? v : r.maps.vertex_copies[v - nv];
}

// CheckRepair of an accepted surface's mesh and vertices: a valid mesh of
// the input's vertices, unmoved, and of copies of them.
inline std::string CheckRepairedVertices(const RawMesh& raw, const RepairedMesh& r) {
  const int32_t nv = static_cast<int32_t>(raw.positions.size());
  const Mesh& m = r.mesh;
  // Valid: Mesh::Create takes the arrays again.
  MeshOptions options;
  options.allow_zero_area_faces = true;
  if (absl::StatusOr<Mesh> again = Mesh::Create(m.positions(), m.faces(), "again", options);
      !again.ok()) {
    return absl::StrCat("the repaired mesh is not valid: ", again.status().ToString());
  }
  if (!OrientableOnceCut(raw)) return "accepted a surface that is not orientable once cut";
  if (r.maps.num_input_vertices != nv) return "num_input_vertices is not the input's";
  const int32_t copies = static_cast<int32_t>(r.maps.vertex_copies.size());
  if (m.num_vertices() != nv + copies) return "vertex count is not input vertices + copies";
  for (int32_t k = 0; k < copies; ++k) {
    const int32_t original = r.maps.vertex_copies[k];
    if (original < 0 || original >= nv) return "a vertex copy of no input vertex";
    if (m.position(nv + k) != raw.positions[original]) return "a copy moved from its original";
  }
  for (int32_t v = 0; v < nv; ++v) {
    if (m.position(v) != raw.positions[v]) return absl::StrCat("input vertex ", v, " moved");
  }
  return "";
}

// For each input face, the first input face with its vertex set (itself
// when it is the first); `distinct` is the number of vertex sets.
inline std::vector<int32_t> FirstOfVertexSet(const RawMesh& raw, int32_t* distinct) {
  const int32_t nf = static_cast<int32_t>(raw.triangles.size());
  std::map<std::array<int32_t, 3>, int32_t> first;
  std::vector<int32_t> keeper(nf);
  *distinct = 0;
  for (int32_t f = 0; f < nf; ++f) {
    std::array<int32_t, 3> key = raw.triangles[f];
    std::sort(key.begin(), key.end());
    const auto [it, inserted] = first.emplace(key, f);
    keeper[f] = it->second;
    *distinct += inserted ? 1 : 0;
  }
  return keeper;
}

// Input face f's corners, mapped by `in`: a permutation onto its internal
// face's corners, each its input vertex, unmoved.
inline std::string CheckInputCorners(const RawMesh& raw, const RepairedMesh& r, int32_t f,
                                     const InputFace& in) {
  std::array<bool, 3> used = {false, false, false};
  for (int i = 0; i < 3; ++i) {
    const int c = in.corner[i];
    if (c > 2 || used[c]) return absl::StrCat("input face ", f, ": not a corner permutation");
    used[c] = true;
    const int32_t v = r.mesh.face(in.face)[c];
    if (InputVertexOf(raw, r, v) != raw.triangles[f][i]) {
      return absl::StrCat("input face ", f, " corner ", i, " is not its input vertex");
    }
    if (r.mesh.position(v) != raw.positions[raw.triangles[f][i]]) {
      return absl::StrCat("input face ", f, " corner ", i, " moved");
    }
  }
  return "";
}

// CheckRepair of the face map: each input face kept in input order, or
// dropped as a duplicate answering for its keeper's face, with its corners;
// the counts as reported. Fills `internal_of`, the internal face of each
// kept input face.
inline std::string CheckFaceMap(const RawMesh& raw, const RepairedMesh& r,
                                const std::vector<int32_t>& keeper,
                                std::vector<int32_t>* internal_of) {
  const int32_t nf = static_cast<int32_t>(raw.triangles.size());
  int32_t dropped = 0, reoriented = 0, next_internal = 0;
  internal_of->assign(nf, kNone);
  for (int32_t f = 0; f < nf; ++f) {
    const InputFace in = r.maps.faces.empty() ? InputFace{f} : r.maps.faces[f];
    if (in.face < 0 || in.face >= r.mesh.num_faces()) {
      return absl::StrCat("input face ", f, " lost");
    }
    if (in.dropped != (keeper[f] != f)) {
      return absl::StrCat(
          "input face ", f,
          in.dropped ? " dropped but first of its vertex set" : " kept but a duplicate");
    }
    if (in.dropped) {
      ++dropped;
      if (in.face != (*internal_of)[keeper[f]]) {
        return absl::StrCat("duplicate ", f, " answers for another face than its twin's");
      }
    } else {
      if (in.face != next_internal++) return "kept faces out of input order";
      (*internal_of)[f] = in.face;
      reoriented += in.reoriented ? 1 : 0;
      const std::array<uint8_t, 3> expected =
          in.reoriented ? std::array<uint8_t, 3>{0, 2, 1} : std::array<uint8_t, 3>{0, 1, 2};
      if (in.corner != expected) return absl::StrCat("input face ", f, ": corner map");
    }
    if (std::string wrong = CheckInputCorners(raw, r, f, in); !wrong.empty()) return wrong;
  }
  if (dropped != r.report.duplicate_faces) return "duplicate count differs from the report";
  if (reoriented != r.report.reoriented_faces) return "re-oriented count differs from the report";
  return "";
}

// Every input edge of exactly two (kept) faces stays joined: cuts are made
// only where more than two faces meet; the cuts as reported.
inline std::string CheckEdgesJoined(const RawMesh& raw, const RepairedMesh& r,
                                    const std::vector<int32_t>& keeper,
                                    const std::vector<int32_t>& internal_of) {
  const int32_t nf = static_cast<int32_t>(raw.triangles.size());
  const Mesh& m = r.mesh;
  std::map<std::pair<int32_t, int32_t>, std::vector<int32_t>> edge_halfedges;
  for (int32_t f = 0; f < nf; ++f) {
    if (keeper[f] != f) continue;
    const int32_t k = internal_of[f];
    for (int i = 0; i < 3; ++i) {
      const int32_t h = 3 * k + i;
      const int32_t a = InputVertexOf(raw, r, m.Origin(h)), b = InputVertexOf(raw, r, m.Dest(h));
      edge_halfedges[{std::min(a, b), std::max(a, b)}].push_back(h);
    }
  }
  int32_t nonmanifold = 0, edge_copies = 0;
  for (const auto& [edge, halves] : edge_halfedges) {
    if (halves.size() == 2 && m.Twin(halves[0]) != halves[1]) {
      return absl::StrFormat("input edge (%d, %d) of two faces was cut", edge.first, edge.second);
    }
    if (halves.size() > 2) {
      ++nonmanifold;
      for (int32_t h : halves) edge_copies += m.Twin(h) == kNone || m.Twin(h) > h ? 1 : 0;
    }
  }
  if (nonmanifold != r.report.nonmanifold_edges || edge_copies != r.report.edge_copies) {
    return "non-manifold edge counts differ from the report";
  }
  return "";
}

// "" when `result` is what RepairMesh promises for `raw`, else what is wrong.
inline std::string CheckRepair(const RawMesh& raw, const absl::StatusOr<RepairedMesh>& result) {
  const int32_t nf = static_cast<int32_t>(raw.triangles.size());
  if (!result.ok()) return CheckRefusal(raw, result.status());
  const RepairedMesh& r = *result;
  if (std::string wrong = CheckRepairedVertices(raw, r); !wrong.empty()) return wrong;
  // One internal face per distinct vertex set, the first of each in input
  // order, in input order.
  int32_t distinct = 0;
  const std::vector<int32_t> keeper = FirstOfVertexSet(raw, &distinct);
  if (r.mesh.num_faces() != distinct) {
    return absl::StrFormat("%d internal faces for %d distinct input faces", r.mesh.num_faces(),
                           distinct);
  }
  if (!r.maps.faces.empty() && static_cast<int32_t>(r.maps.faces.size()) != nf) {
    return "a face map that is not one entry per input face";
  }
  std::vector<int32_t> internal_of;
  if (std::string wrong = CheckFaceMap(raw, r, keeper, &internal_of); !wrong.empty()) return wrong;
  const int32_t copies = static_cast<int32_t>(r.maps.vertex_copies.size());
  if (r.report.vertex_copies - r.report.nonmanifold_vertices != copies) {
    return "vertex copies differ from the report";
  }
  return CheckEdgesJoined(raw, r, keeper, internal_of);
}

// Whether two repairs of one input made the same mesh and maps.
inline bool SameRepair(const RepairedMesh& a, const RepairedMesh& b) {
  if (a.mesh.positions() != b.mesh.positions() || a.mesh.faces() != b.mesh.faces()) return false;
  if (a.maps.vertex_copies != b.maps.vertex_copies || a.maps.faces.size() != b.maps.faces.size()) {
    return false;
  }
  for (size_t f = 0; f < a.maps.faces.size(); ++f) {
    const InputFace &x = a.maps.faces[f], &y = b.maps.faces[f];
    if (x.face != y.face || x.corner != y.corner || x.dropped != y.dropped ||
        x.reoriented != y.reoriented) {
      return false;
    }
  }
  return a.report.ToText() == b.report.ToText();
}

}  // namespace geodex::mesh::testing
