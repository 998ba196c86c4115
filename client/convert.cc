#include "client/convert.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace geodex::client {
namespace {

// Appends points at(begin) .. at(end - 1) to `out`: their faces and weights,
// and their vertex ids when any is a vertex (SurfacePoint::Vertex); only the
// ids when all are (geodex.proto's SurfacePoints).
template <typename At>
void AppendPoints(size_t begin, size_t end, At at, v1::SurfacePoints* out) {
  bool any_vertex = false, all_vertices = true;
  for (size_t i = begin; i < end; ++i) {
    const bool vertex = at(i).vertex >= 0;
    any_vertex |= vertex;
    all_vertices &= vertex;
  }
  const int n = static_cast<int>(end - begin);
  if (any_vertex) {
    out->mutable_vertices()->Reserve(out->vertices_size() + n);
    for (size_t i = begin; i < end; ++i) out->add_vertices(std::max(at(i).vertex, -1));
    if (all_vertices) return;
  }
  out->mutable_faces()->Reserve(out->faces_size() + n);
  out->mutable_weights()->Reserve(out->weights_size() + 3 * n);
  for (size_t i = begin; i < end; ++i) {
    const SurfacePoint& p = at(i);
    out->add_faces(p.face);
    for (double w : p.w) out->add_weights(w);
  }
}

}  // namespace

v1::ModelRef ToProto(const ModelRef& model) {
  v1::ModelRef ref;
  ref.set_name(model.name);
  ref.set_version(model.version);
  return ref;
}

v1::NearPairs ToProto(NearPairs mode) {
  switch (mode) {
    case NearPairs::kPath:
      return v1::NEAR_PAIRS_PATH;
    case NearPairs::kUnfold:
      return v1::NEAR_PAIRS_UNFOLD;
    case NearPairs::kExact:
      return v1::NEAR_PAIRS_EXACT;
    case NearPairs::kModelDefault:
      break;
  }
  return v1::NEAR_PAIRS_UNSPECIFIED;
}

v1::SurfacePoints ToProto(absl::Span<const SurfacePoint> points) {
  v1::SurfacePoints out;
  AppendPoints(0, points.size(), [&](size_t i) -> const SurfacePoint& { return points[i]; }, &out);
  return out;
}

void PairsToProto(absl::Span<const PointPair> pairs, size_t begin, size_t end, v1::SurfacePoints* a,
                  v1::SurfacePoints* b) {
  AppendPoints(begin, end, [&](size_t i) -> const SurfacePoint& { return pairs[i].a; }, a);
  AppendPoints(begin, end, [&](size_t i) -> const SurfacePoint& { return pairs[i].b; }, b);
}

absl::StatusOr<std::vector<SurfacePoint>> FromProto(const v1::SurfacePoints& points) {
  if (points.weights_size() != 3 * points.faces_size()) {
    return absl::DataLossError(absl::StrFormat("the server sent %d faces with %d weights",
                                               points.faces_size(), points.weights_size()));
  }
  std::vector<SurfacePoint> out(points.faces_size());
  for (int i = 0; i < points.faces_size(); ++i) {
    out[i].face = points.faces(i);
    out[i].w = {points.weights(3 * i), points.weights(3 * i + 1), points.weights(3 * i + 2)};
  }
  return out;
}

ModelInfo FromProto(const v1::ModelInfo& m) {
  ModelInfo info;
  info.name = m.name();
  info.version = m.version();
  info.available_versions.assign(m.available_versions().begin(), m.available_versions().end());
  switch (m.state()) {
    case v1::ModelInfo::LOADING:
      info.state = ModelInfo::State::kLoading;
      break;
    case v1::ModelInfo::SERVING:
      info.state = ModelInfo::State::kServing;
      break;
    case v1::ModelInfo::FAILED:
      info.state = ModelInfo::State::kFailed;
      break;
    default:
      info.state = ModelInfo::State::kUnspecified;
  }
  info.reason = m.reason();
  info.num_vertices = m.num_vertices();
  info.num_faces = m.num_faces();
  info.num_samples = m.num_samples();
  info.num_triangles = m.num_triangles();
  for (int i = 0; i < 3 && i < m.bbox_min_size(); ++i) info.bbox_min[i] = m.bbox_min(i);
  for (int i = 0; i < 3 && i < m.bbox_max_size(); ++i) info.bbox_max[i] = m.bbox_max(i);
  info.requested_samples = m.requested_samples();
  info.seed = m.seed();
  info.samples_added_by_repair = m.samples_added_by_repair();
  info.builder_version = m.builder_version();
  info.build_report.insert(m.build_report().begin(), m.build_report().end());
  info.mapped_bytes = m.mapped_bytes();
  info.mesh_hash = m.mesh_hash();
  info.report_json = m.report_json();
  return info;
}

absl::Status CheckModel(const ModelRef& model) {
  if (model.name.empty()) return absl::InvalidArgumentError("no model name given");
  if (model.version < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("model version ", model.version, " is negative (0 means the newest)"));
  }
  return absl::OkStatus();
}

}  // namespace geodex::client
