#pragma once

// The input mesh's ids over an index of a repaired mesh: the one place where
// requests in input ids become the index's internal ids and answers go back.
//
// An index of a mesh the builder repaired (core/mesh/mesh_repair.h, index
// format 1.2) answers internally on the repaired mesh: duplicate faces
// dropped, faces re-oriented, non-manifold vertices split into copies. Its
// callers keep the ids of the file they built it from:
//   - a point (input face f, weights w) is the point of f's internal face
//     with the weights permuted as f's corners are (a re-oriented face swaps
//     corners 1 and 2); a dropped duplicate answers as its twin;
//   - an internal point goes back to the input face that was kept for its
//     face, weights permuted back;
//   - per-vertex answers are per input vertex; where an input vertex was
//     split, the smallest of its copies' values is given (its distance from
//     the nearest source, the smallest r of an exponential map): the copies
//     are the same point of space, reached through different sheets, and the
//     shortest way to it is the answer.
// The face count clients see is the input's, so that face ids are validated
// against the input's range.
//
// An index of a mesh with split long edges (format 2.0) adds a second step: the repaired
// ("coarse") faces were split flat, so a coarse point is located among its
// face's pieces (the piece whose weights hold it), and an internal point goes
// back through its piece's corner weights. The midpoints are no input
// vertices: per-vertex answers leave them out, and a sample placed on one is
// named by its surface point only.
//
// An index without the sections (not repaired, or older than 1.2) has
// identity maps: every method returns its argument, and nothing is copied.
//
// Thread safety: immutable after construction; every method is const and
// thread-safe.

#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

class InputIds {
 public:
  // `index` must outlive this object.
  explicit InputIds(const index::Index& index);

  // True when input ids are internal ids.
  bool identity() const {
    return input_faces_.empty() && vertex_copies_.empty() && !split();
  }
  // True for an index of a mesh whose long edges were split (format 2.0).
  bool split() const { return split_->split(); }
  int32_t num_input_faces() const { return num_input_faces_; }
  int32_t num_input_vertices() const { return num_input_vertices_; }

  // Validates `p` against the input's face count (mesh::ValidateSurfacePoint:
  // OutOfRange for a face id past the end, InvalidArgument for bad weights)
  // and returns it as an internal point.
  absl::StatusOr<mesh::SurfacePoint> ToInternal(const mesh::SurfacePoint& p,
                                                double tolerance = 1e-6) const;
  // A point of the mesh before the long-edge split (the repaired mesh,
  // whose vertices are the index's first ones; face in range, weights a
  // partition of 1) as an internal point: the piece of its face that holds
  // it, or the point itself without the split. Errors: Internal when no
  // piece of its face can hold it.
  absl::StatusOr<mesh::SurfacePoint> CoarseToInternal(const mesh::SurfacePoint& coarse) const;
  // An internal point in the input face kept for its face.
  mesh::SurfacePoint ToInput(const mesh::SurfacePoint& p) const;
  // Internal vertices that are a repair's copy of an input vertex: ids
  // [num_input_vertices, num_input_vertices + num_vertex_copies).
  int32_t num_vertex_copies() const { return static_cast<int32_t>(vertex_copies_.size()); }
  // The input vertex internal vertex `v` is (a copy's original), or
  // mesh::kNone for a midpoint of the split.
  int32_t InputVertex(int32_t v) const {
    if (v < num_input_vertices_) return v;
    const int32_t k = v - num_input_vertices_;
    return k < num_vertex_copies() ? vertex_copies_[k] : mesh::kNone;
  }
  // True when input face `f` (in range) had its corners 1 and 2 swapped.
  bool Reoriented(int32_t f) const;
  // The input vertices of input face `f` (in range), in the input's order.
  mesh::Triangle InputFace(int32_t f) const;

  // A per-internal-vertex field as a per-input-vertex one: at a split
  // vertex, the smallest distance of its copies and that copy's nearest
  // source.
  DistanceField FieldToInput(DistanceField field) const;
  // Path points in input faces (positions unchanged).
  void PathToInput(std::span<PathPoint> path) const;

 private:
  const index::Index* index_;
  std::span<const index::InputFaceRecord> input_faces_;
  std::span<const int32_t> vertex_copies_;
  int32_t num_input_faces_ = 0;
  int32_t num_input_vertices_ = 0;
  // Coarse face -> the input face kept for it; empty for identity faces.
  std::vector<int32_t> kept_input_face_;
  // The long-edge split (empty without): per coarse face, its pieces
  // pieces_[piece_offset_[c], piece_offset_[c + 1]).
  const index::SplitView* split_;
  std::vector<int32_t> piece_offset_;
  std::vector<int32_t> pieces_;
};

}  // namespace geodex::query
