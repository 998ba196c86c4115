#pragma once

// Mesh repair: what can be repaired of a broken triangle soup without
// changing the surface, each repair counted, with the maps back to the
// input's ids.
//
//   - Duplicate faces (the same three vertices, in any order) are dropped: the
//     first of each group in input order stays and answers for the others.
//   - Unreferenced vertices are ignored (kept, on no face; Mesh allows them).
//   - Inconsistently oriented faces are re-oriented (corners 1 and 2 swapped)
//     so that faces agree across every edge they share, each connected part
//     keeping the orientation most of its faces have.
//   - Non-manifold edges (more than two faces, in any orientations) are cut:
//     every face round such an edge is paired with at most one other, and a
//     face left unpaired keeps the edge as a boundary (its own copy). Faces
//     are ordered round the edge, and a face is paired with the next one
//     counter-clockwise when their orientations say the space between them
//     is the inside of one solid: two closed solids touching along an edge
//     each keep their own copy of it, and the pages of a "book" become
//     sheets of their own. Then, where two copies of the edge would still
//     join the same two vertices (two sheets crossing along the edge, whose
//     faces the solid rule paired across the sheets), those copies are undone
//     and the faces that meet round both ends are paired instead: each sheet
//     keeps its own copy.
//   - Non-manifold vertices (faces round a vertex in several fans, including
//     the fans the edge cuts make) are split into one vertex per fan: the fan
//     of the lowest face keeps the id, the copies are appended after the
//     input's vertices, at the same position.
//   - Zero-area and sliver faces are kept (MeshOptions::allow_zero_area_faces).
//
// Refused (InvalidArgument, with the reason, messages as Mesh::Create's): no
// faces, NaN or infinite coordinates, corner ids out of range, a triangle (or
// a file polygon) with a repeated vertex, and a surface that is not orientable
// once its non-manifold edges are cut (a Möbius strip). Never because a cut
// could not be made: any other soup of triangles becomes a valid Mesh. With
// RepairOptions::strict nothing is repaired: the mesh is refused with the
// first reason Mesh::Create finds, exactly as before repair existed
// (unreferenced vertices, which were always accepted, stay accepted).
//
// Ids. The internal mesh's faces are the kept input triangles in input order,
// each with its three input positions; its vertices are the input's, then the
// copies. RepairMaps says where each input triangle went and how its corners
// permute, and which input vertex each copy stands for. Input ids are those
// of mesh_io.h (triangles after fan triangulation of the file's polygons; the
// welded vertices of STL and glTF files).
//
// Thread safety: pure functions.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"

namespace geodex::mesh {

struct RepairOptions {
  // Refuse instead of repairing (geodex-build --strict).
  bool strict = false;
  // How LoadAndRepairMesh reads the file (geodex-build --weld).
  ReadOptions read;
};

// How many of each repair were made.
struct RepairReport {
  int32_t duplicate_faces = 0;        // input triangles dropped
  int32_t unreferenced_vertices = 0;  // input vertices on no face
  int32_t nonmanifold_edges = 0;      // edges of more than two faces, cut
  int32_t edge_copies = 0;            // the edges those became (paired sheets and single faces)
  int32_t nonmanifold_vertices = 0;   // input vertices split
  int32_t vertex_copies = 0;          // the vertices those became (the originals included)
  int32_t reoriented_faces = 0;
  int32_t zero_area_faces = 0;  // kept
  int32_t sliver_faces = 0;     // kept: doubled area under 1e-6 of the longest squared edge
  // What the reader's welding did (RawMesh::weld; STL and glTF files only).
  WeldReport weld;

  // True when the internal mesh differs from the input's triangles.
  bool changed() const {
    return duplicate_faces + nonmanifold_edges + nonmanifold_vertices + reoriented_faces > 0;
  }
  // One line: "1 non-manifold vertex split (2 copies), 0 non-manifold edges
  // cut (0 copies), 0 duplicate faces dropped, ...", ending, for a welded
  // file, with "; 1234 corners welded".
  std::string Summary() const;
  // "key = value" lines for the build report: mesh_repairs = Summary(), then
  // one count per key (mesh_duplicate_faces_dropped, ...), and for a welded
  // file mesh_welded_corners, mesh_weld_tolerance and
  // mesh_degenerate_corners_unwelded.
  std::string ToText() const;
};

// Where one input triangle went.
struct InputFace {
  int32_t face = 0;  // internal face; for a dropped duplicate, that of the face it duplicates
  // Input corner i is internal corner corner[i]: weights w of the input face
  // are w'[corner[i]] = w[i] on the internal one.
  std::array<uint8_t, 3> corner = {0, 1, 2};
  bool dropped = false;
  bool reoriented = false;
};

struct RepairMaps {
  int32_t num_input_vertices = 0;
  // One per input triangle; empty when every input triangle is the internal
  // face of the same id with the same corners.
  std::vector<InputFace> faces;
  // vertex_copies[k]: the input vertex internal vertex num_input_vertices + k
  // is a copy of.
  std::vector<int32_t> vertex_copies;

  bool identity() const { return faces.empty() && vertex_copies.empty(); }
};

struct RepairedMesh {
  Mesh mesh;  // the internal mesh
  RepairMaps maps;
  RepairReport report;
};

// Repairs `raw` (see the header comment). Errors: InvalidArgument for what
// cannot be repaired, or with options.strict for anything that needs a repair,
// naming the element ("<name>: non-manifold vertex 12: ..."); a file of
// polygons adds that face ids count triangles. Internal would be a defect of
// the repair (it made a mesh Mesh::Create refuses), never of the input.
absl::StatusOr<RepairedMesh> RepairMesh(RawMesh raw, const RepairOptions& options = {});

// LoadRawMeshFile (read as options.read says), then RepairMesh.
absl::StatusOr<RepairedMesh> LoadAndRepairMesh(const std::string& path,
                                               const RepairOptions& options = {});

// A valid mesh as a repaired one with nothing repaired (identity maps), e.g.
// a generated mesh.
RepairedMesh WithoutRepairs(Mesh mesh);

}  // namespace geodex::mesh
