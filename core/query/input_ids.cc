#include "core/query/input_ids.h"

#include <algorithm>
#include <numbers>
#include <utility>

#include "core/common/status_macros.h"

namespace geodex::query {

InputIds::InputIds(const index::Index& index)
    : index_(&index),
      input_faces_(index.input_faces()),
      vertex_copies_(index.vertex_copies()),
      num_input_faces_(input_faces_.empty() ? index.num_faces()
                                            : static_cast<int32_t>(input_faces_.size())),
      num_input_vertices_(index.num_vertices() - static_cast<int32_t>(vertex_copies_.size())) {
  if (input_faces_.empty()) return;
  // Index::Open checked that every internal face is kept for exactly one
  // input face.
  kept_input_face_.assign(index.num_faces(), mesh::kNone);
  for (int32_t f = 0; f < num_input_faces_; ++f) {
    const index::InputFaceRecord& r = input_faces_[f];
    if ((r.flags & index::kInputFaceDropped) == 0) kept_input_face_[r.face] = f;
  }
}

absl::StatusOr<mesh::SurfacePoint> InputIds::ToInternal(const mesh::SurfacePoint& p,
                                                        double tolerance) const {
  GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(num_input_faces_, p, tolerance));
  if (input_faces_.empty()) return p;
  const index::InputFaceRecord& r = input_faces_[p.face];
  mesh::SurfacePoint out{r.face, {0, 0, 0}};
  for (int i = 0; i < 3; ++i) out.w[r.corner[i]] = p.w[i];
  return out;
}

mesh::SurfacePoint InputIds::ToInput(const mesh::SurfacePoint& p) const {
  if (input_faces_.empty()) return p;
  const int32_t f = kept_input_face_[p.face];
  const index::InputFaceRecord& r = input_faces_[f];
  mesh::SurfacePoint out{f, {0, 0, 0}};
  for (int i = 0; i < 3; ++i) out.w[i] = p.w[r.corner[i]];
  return out;
}

bool InputIds::Reoriented(int32_t f) const {
  return !input_faces_.empty() && (input_faces_[f].flags & index::kInputFaceReoriented) != 0;
}

mesh::Triangle InputIds::InputFace(int32_t f) const {
  const std::span<const int32_t> faces = index_->faces();
  mesh::Triangle out;
  if (input_faces_.empty()) {
    for (int i = 0; i < 3; ++i) out[i] = InputVertex(faces[3 * f + i]);
    return out;
  }
  const index::InputFaceRecord& r = input_faces_[f];
  for (int i = 0; i < 3; ++i) out[i] = InputVertex(faces[3 * r.face + r.corner[i]]);
  return out;
}

DistanceField InputIds::FieldToInput(DistanceField field) const {
  if (vertex_copies_.empty()) return field;
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
  if (input_faces_.empty()) return;
  for (PathPoint& p : path) p.point = ToInput(p.point);
}

absl::StatusOr<std::vector<ExpMapVertex>> ExpMapOfInput(const QueryEngine& engine,
                                                        const mesh::SurfacePoint& centre,
                                                        ExpMapOptions options,
                                                        QueryScratch* scratch) {
  const InputIds& ids = engine.input_ids();
  GEODEX_ASSIGN_OR_RETURN(const mesh::SurfacePoint internal,
                          ids.ToInternal(centre, engine.options().weight_tolerance));
  // A re-oriented face's normal is the input face's reversed, and its first
  // edge another edge: give the input's first edge, and mirror θ.
  const bool mirrored = ids.Reoriented(centre.face);
  if (mirrored && !options.reference_direction.has_value()) {
    const mesh::Triangle t = ids.InputFace(centre.face);
    const std::span<const double> p = engine.index().positions();
    options.reference_direction = mesh::Vec3(p[3 * t[1]], p[3 * t[1] + 1], p[3 * t[1] + 2]) -
                                  mesh::Vec3(p[3 * t[0]], p[3 * t[0] + 1], p[3 * t[0] + 2]);
  }
  GEODEX_ASSIGN_OR_RETURN(std::vector<ExpMapVertex> map,
                          ExpMap(engine, internal, options, scratch));
  if (ids.identity()) return map;
  for (ExpMapVertex& e : map) {
    e.vertex = ids.InputVertex(e.vertex);
    if (mirrored) {
      e.theta = e.theta == 0 || e.theta == std::numbers::pi ? e.theta : -e.theta;
      e.v = -e.v;
    }
  }
  // One entry per input vertex: the copy of smallest r.
  std::stable_sort(map.begin(), map.end(), [](const ExpMapVertex& a, const ExpMapVertex& b) {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.r < b.r;
  });
  map.erase(std::unique(
                map.begin(), map.end(),
                [](const ExpMapVertex& a, const ExpMapVertex& b) { return a.vertex == b.vertex; }),
            map.end());
  return map;
}

}  // namespace geodex::query
