#include "core/query/engine/input_ids.h"

#include <algorithm>
#include <array>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::query {

InputIds::InputIds(const index::Index& index)
    : index_(&index),
      input_faces_(index.input_faces()),
      vertex_copies_(index.vertex_copies()),
      num_input_vertices_(index.num_vertices() - index.split_vertices() -
                          static_cast<int32_t>(index.vertex_copies().size())),
      split_(&index.split()) {
  const int32_t num_coarse_faces = split() ? split_->num_coarse_faces() : index.num_faces();
  num_input_faces_ =
      input_faces_.empty() ? num_coarse_faces : static_cast<int32_t>(input_faces_.size());
  if (split()) {
    // Index::Open checked that every piece names a coarse face and every
    // coarse face has one.
    const int32_t nf = index.num_faces();
    std::vector<int32_t> coarse_of(nf);
    piece_offset_.assign(num_coarse_faces + 1, 0);
    for (int32_t f = 0; f < nf; ++f)
      ++piece_offset_[(coarse_of[f] = split_->Piece(f).coarse_face) + 1];
    for (int32_t c = 0; c < num_coarse_faces; ++c) piece_offset_[c + 1] += piece_offset_[c];
    pieces_.resize(nf);
    std::vector<int32_t> cursor(piece_offset_.begin(), piece_offset_.end() - 1);
    for (int32_t f = 0; f < nf; ++f) pieces_[cursor[coarse_of[f]]++] = f;
  }
  if (input_faces_.empty()) return;
  // Index::Open checked that every coarse face is kept for exactly one
  // input face.
  kept_input_face_.assign(num_coarse_faces, mesh::kNone);
  for (int32_t f = 0; f < num_input_faces_; ++f) {
    const index::InputFaceRecord& r = input_faces_[f];
    if ((r.flags & index::kInputFaceDropped) == 0) kept_input_face_[r.face] = f;
  }
}

absl::StatusOr<mesh::SurfacePoint> InputIds::ToInternal(const mesh::SurfacePoint& p,
                                                        double tolerance) const {
  GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(num_input_faces_, p, tolerance));
  mesh::SurfacePoint coarse = p;
  if (!input_faces_.empty()) {
    const index::InputFaceRecord& r = input_faces_[p.face];
    coarse = {r.face, {0, 0, 0}};
    for (int i = 0; i < 3; ++i) coarse.w[r.corner[i]] = p.w[i];
  }
  return CoarseToInternal(coarse);
}

absl::StatusOr<mesh::SurfacePoint> InputIds::CoarseToInternal(
    const mesh::SurfacePoint& coarse) const {
  if (!split()) return coarse;
  // The first piece holding the point (no weight negative; on a shared edge
  // either is right), else the one whose smallest weight is the largest:
  // rounding may leave the point a hair outside every piece. Stopping at the
  // first matters on a coarse face of many pieces.
  mesh::SurfacePoint best{mesh::kNone, {0, 0, 0}};
  double best_min = -std::numeric_limits<double>::infinity();
  for (int32_t k = piece_offset_[coarse.face]; k < piece_offset_[coarse.face + 1]; ++k) {
    const index::SplitFaceRecord r = split_->Piece(pieces_[k]);
    // coarse.w = a0 W0 + a1 W1 + a2 W2 with a0 + a1 + a2 = 1: two
    // equations in the first two weights (the third follows).
    const double e00 = r.weight[0][0] - r.weight[2][0], e01 = r.weight[1][0] - r.weight[2][0];
    const double e10 = r.weight[0][1] - r.weight[2][1], e11 = r.weight[1][1] - r.weight[2][1];
    const double b0 = coarse.w[0] - r.weight[2][0], b1 = coarse.w[1] - r.weight[2][1];
    const double det = e00 * e11 - e01 * e10;
    if (det == 0) continue;  // Index::Open does not rule out a flat piece
    const double a0 = (b0 * e11 - e01 * b1) / det, a1 = (e00 * b1 - b0 * e10) / det;
    const double a2 = 1 - a0 - a1;
    const double smallest = std::min({a0, a1, a2});
    if (smallest > best_min) {
      best_min = smallest;
      best = {pieces_[k], {a0, a1, a2}};
      if (smallest >= 0) break;
    }
  }
  if (best.face == mesh::kNone) {
    return absl::InternalError(absl::StrFormat("coarse face %d has no usable piece", coarse.face));
  }
  // Clamp what rounding left outside, keeping the weights a partition of 1.
  double sum = 0;
  for (double& w : best.w) sum += (w = std::max(w, 0.0));
  for (double& w : best.w) w /= sum;
  return best;
}

mesh::SurfacePoint InputIds::ToInput(const mesh::SurfacePoint& p) const {
  mesh::SurfacePoint coarse = p;
  if (split()) {
    const index::SplitFaceRecord r = split_->Piece(p.face);
    coarse = {r.coarse_face, {0, 0, 0}};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) coarse.w[j] += p.w[i] * r.weight[i][j];
    }
  }
  if (input_faces_.empty()) return coarse;
  const int32_t f = kept_input_face_[coarse.face];
  const index::InputFaceRecord& r = input_faces_[f];
  mesh::SurfacePoint out{f, {0, 0, 0}};
  for (int i = 0; i < 3; ++i) out.w[i] = coarse.w[r.corner[i]];
  return out;
}

bool InputIds::Reoriented(int32_t f) const {
  return !input_faces_.empty() && (input_faces_[f].flags & index::kInputFaceReoriented) != 0;
}

mesh::Triangle InputIds::InputFace(int32_t f) const {
  auto corners = [&](int32_t c) -> std::array<int32_t, 3> {
    if (split()) return split_->CoarseFace(c);
    const std::span<const int32_t> faces = index_->faces();
    return {faces[3 * c], faces[3 * c + 1], faces[3 * c + 2]};
  };
  mesh::Triangle out;
  if (input_faces_.empty()) {
    const std::array<int32_t, 3> c = corners(f);
    for (int i = 0; i < 3; ++i) out[i] = InputVertex(c[i]);
    return out;
  }
  const index::InputFaceRecord& r = input_faces_[f];
  const std::array<int32_t, 3> c = corners(r.face);
  for (int i = 0; i < 3; ++i) out[i] = InputVertex(c[r.corner[i]]);
  return out;
}

DistanceField InputIds::FieldToInput(DistanceField field) const {
  if (vertex_copies_.empty() && !split()) return field;
  for (size_t k = 0; k < vertex_copies_.size(); ++k) {
    const size_t copy = num_input_vertices_ + k, v = vertex_copies_[k];
    if (field.distance[copy] < field.distance[v]) {
      field.distance[v] = field.distance[copy];
      field.nearest[v] = field.nearest[copy];
    }
  }
  field.distance.resize(num_input_vertices_);
  field.nearest.resize(num_input_vertices_);
  return field;
}

void InputIds::PathToInput(std::span<PathPoint> path) const {
  if (input_faces_.empty() && !split()) return;
  for (PathPoint& p : path) p.point = ToInput(p.point);
}

}  // namespace geodex::query
