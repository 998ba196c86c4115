#include "server/convert/convert.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "core/common/status_macros.h"
#include "core/index/index_report.h"

namespace geodex::server {

absl::Status PointsFromProto(const v1::SurfacePoints& points, std::string_view name,
                             const query::InputQueries& queries, query::EnginePoints* out) {
  const std::span<const int32_t> faces(points.faces().data(), points.faces_size());
  const std::span<const double> weights(points.weights().data(), points.weights_size());
  if (points.vertices_size() > 0) {
    const std::span<const int32_t> vertices(points.vertices().data(), points.vertices_size());
    return queries.Read(faces, weights, vertices, query::Named(name), out);
  }
  if (weights.size() != 3 * faces.size()) {
    return absl::InvalidArgumentError(absl::StrFormat("%s: %d faces but %d weights (want %d)",
                                                      std::string(name), faces.size(),
                                                      weights.size(), 3 * faces.size()));
  }
  return queries.Read(faces, weights, query::Named(name), out);
}

absl::Status CheckPairedUp(const v1::SurfacePoints& a, const v1::SurfacePoints& b) {
  const int64_t na = PointCount(a), nb = PointCount(b);
  if (na == nb) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrFormat("a has %d points but b has %d; they must pair up", na, nb));
}

absl::Status OnePointFromProto(const v1::SurfacePoints& points, std::string_view name,
                               const query::InputQueries& queries, query::EnginePoints* out) {
  if (PointCount(points) != 1) {
    return absl::InvalidArgumentError(absl::StrFormat("%s: give exactly one point, got %d",
                                                      std::string(name), PointCount(points)));
  }
  return PointsFromProto(points, name, queries, out);
}

absl::Status PositionsFromProto(const v1::Positions& positions, std::string_view name,
                                std::vector<mesh::Vec3>* out) {
  const int64_t size = positions.xyz_size();
  if (size % 3 != 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: %d coordinates, not a multiple of 3", std::string(name), size));
  }
  const int64_t n = size / 3;
  out->resize(n);
  const double* xyz = positions.xyz().data();
  for (int64_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(xyz[3 * i + c])) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "%s[%d]: %c is %g, not finite", std::string(name), i, "xyz"[c], xyz[3 * i + c]));
      }
    }
    (*out)[i] = mesh::Vec3(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  }
  return absl::OkStatus();
}

void AppendPoint(const mesh::SurfacePoint& point, v1::SurfacePoints* points) {
  points->add_faces(point.face);
  for (double w : point.w) points->add_weights(w);
}

std::span<double> ResizeForOutput(google::protobuf::RepeatedField<double>* values, int64_t n) {
  values->Resize(static_cast<int>(n), 0.0);
  return {values->mutable_data(), static_cast<size_t>(n)};
}

void PathToProto(std::span<const query::PathPoint> path, v1::Polyline* polyline) {
  polyline->Clear();
  v1::SurfacePoints* points = polyline->mutable_points();
  google::protobuf::RepeatedField<double>* xyz = polyline->mutable_positions()->mutable_xyz();
  points->mutable_faces()->Reserve(static_cast<int>(path.size()));
  points->mutable_weights()->Reserve(static_cast<int>(3 * path.size()));
  xyz->Reserve(static_cast<int>(3 * path.size()));
  for (const query::PathPoint& p : path) {
    AppendPoint(p.point, points);
    for (int c = 0; c < 3; ++c) xyz->Add(p.position[c]);
  }
  polyline->set_length(query::PathLength(path));
}

void UnreachablePathToProto(v1::Polyline* polyline) {
  polyline->Clear();
  polyline->set_length(std::numeric_limits<double>::infinity());
}

void AppendLocated(const query::LocatedPoint& located, v1::LocateResponse* response) {
  AppendPoint(located.point, response->mutable_points());
  response->add_distances(located.distance);
}

void MatrixBlockToProto(int64_t row_offset, int64_t rows, int64_t num_targets,
                        std::span<const double> values, std::span<const double> bounds,
                        int64_t version, v1::MatrixBlock* block) {
  block->set_row_offset(row_offset);
  block->set_rows(rows);
  block->set_num_targets(num_targets);
  block->set_version(version);
  block->mutable_values()->Assign(values.begin(), values.end());
  block->mutable_bounds()->Assign(bounds.begin(), bounds.end());
}

namespace {

// The part of a chunk both kinds of field share: where it starts, how many
// vertices the field has, the version, and the slice of distances (and
// nearest sources, if asked for).
template <typename Field>
void FieldSliceToProto(const Field& field, size_t num_vertices, int64_t offset, int64_t count,
                       bool with_nearest_source, int64_t version, v1::DistanceFieldChunk* chunk) {
  chunk->set_vertex_offset(offset);
  chunk->set_num_vertices(static_cast<int64_t>(num_vertices));
  chunk->set_version(version);
  chunk->mutable_distances()->Assign(field.distance.begin() + offset,
                                     field.distance.begin() + offset + count);
  if (with_nearest_source) {
    chunk->mutable_nearest_source()->Assign(field.nearest.begin() + offset,
                                            field.nearest.begin() + offset + count);
  } else {
    chunk->clear_nearest_source();
  }
}

}  // namespace

void FieldChunkToProto(const query::DistanceField& field, int64_t offset, int64_t count,
                       bool with_nearest_source, int64_t version, v1::DistanceFieldChunk* chunk) {
  FieldSliceToProto(field, field.distance.size(), offset, count, with_nearest_source, version,
                    chunk);
}

void RadiusFieldChunkToProto(const query::RadiusField& field, int64_t offset, int64_t count,
                             bool with_nearest_source, int64_t version,
                             v1::DistanceFieldChunk* chunk) {
  FieldSliceToProto(field, field.vertices.size(), offset, count, with_nearest_source, version,
                    chunk);
  chunk->mutable_vertices()->Assign(field.vertices.begin() + offset,
                                    field.vertices.begin() + offset + count);
}

void MeshChunkToProto(const query::InputQueries& queries, int64_t vertex_offset,
                      int64_t vertex_count, int64_t face_offset, int64_t face_count,
                      int64_t version, v1::MeshChunk* chunk) {
  const index::Index& index = queries.index();
  assert(vertex_offset >= 0 && vertex_count >= 0 &&
         vertex_offset + vertex_count <= queries.num_vertices());
  assert(face_offset >= 0 && face_count >= 0 && face_offset + face_count <= queries.num_faces());
  chunk->set_num_vertices(static_cast<uint32_t>(queries.num_vertices()));
  chunk->set_num_faces(static_cast<uint32_t>(queries.num_faces()));
  chunk->set_version(version);
  chunk->set_vertex_offset(static_cast<uint32_t>(vertex_offset));
  chunk->set_face_offset(static_cast<uint32_t>(face_offset));
  // The input's vertices are the index's first ones (copies and midpoints
  // come after).
  const std::span<const double> positions =
      index.positions().subspan(3 * vertex_offset, 3 * vertex_count);
  chunk->mutable_positions()->Assign(positions.begin(), positions.end());
  google::protobuf::RepeatedField<uint32_t>* out = chunk->mutable_faces();
  out->Clear();
  out->Reserve(static_cast<int>(3 * face_count));
  if (queries.identity()) {
    // Vertex ids are int32 in the index and >= 0 (Index::Open checks them).
    const std::span<const int32_t> faces = index.faces().subspan(3 * face_offset, 3 * face_count);
    for (const int32_t v : faces) out->AddAlreadyReserved(static_cast<uint32_t>(v));
    return;
  }
  for (int64_t f = face_offset; f < face_offset + face_count; ++f) {
    for (const int32_t v : queries.InputFace(static_cast<int32_t>(f))) {
      out->AddAlreadyReserved(static_cast<uint32_t>(v));
    }
  }
}

void TriangulationToProto(const query::InputQueries& queries, int64_t version,
                          v1::TriangulationResponse* out) {
  const index::Index& index = queries.index();
  out->set_version(version);
  out->set_num_vertices(queries.num_vertices());
  const std::span<const int32_t> samples = index.samples();
  const std::span<const double> positions = index.positions();
  const std::vector<mesh::SurfacePoint> points = queries.SamplePoints();
  for (size_t i = 0; i < samples.size(); ++i) {
    const size_t v = static_cast<size_t>(samples[i]);
    out->add_sample_vertices(queries.InputVertex(samples[i]));
    for (int k = 0; k < 3; ++k) out->mutable_sample_positions()->add_xyz(positions[3 * v + k]);
    AppendPoint(points[i], out->mutable_sample_points());
  }
  for (const index::GeodesicTriangle& t : index.triangles()) {
    for (int k = 0; k < 3; ++k) {
      out->add_triangle_corners(t.corner[k]);
      out->add_triangle_neighbors(t.neighbor[k]);
    }
  }
  const std::vector<int32_t> vertex_triangles = queries.VertexTriangles();
  out->mutable_vertex_triangles()->Assign(vertex_triangles.begin(), vertex_triangles.end());
}

namespace {

v1::ModelInfo::State ToProtoState(LoadState state) {
  switch (state) {
    case LoadState::kLoading:
      return v1::ModelInfo::LOADING;
    case LoadState::kServing:
      return v1::ModelInfo::SERVING;
    case LoadState::kFailed:
      return v1::ModelInfo::FAILED;
  }
  return v1::ModelInfo::STATE_UNSPECIFIED;
}

}  // namespace

void ModelInfoToProto(const ModelSnapshot& model, const ServedVersion* version,
                      v1::ModelInfo* info) {
  info->Clear();
  info->set_name(model.name);
  info->set_state(ToProtoState(model.state));
  info->set_reason(model.reason);
  for (int64_t v : model.available_versions) info->add_available_versions(v);
  if (version == nullptr) {
    info->set_version(model.available_versions.empty() ? 0 : model.available_versions.back());
    return;
  }
  const index::Index& ix = version->index();
  const index::FileHeader& h = ix.header();
  info->set_version(version->version());
  info->set_num_vertices(version->queries().num_vertices());
  info->set_num_faces(version->queries().num_faces());
  info->set_num_samples(ix.num_samples());
  info->set_num_triangles(ix.num_triangles());
  if (ix.num_vertices() > 0) {
    std::span<const double> p = ix.positions();
    double lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
    for (size_t v = 0; v < p.size() / 3; ++v) {
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], p[3 * v + c]);
        hi[c] = std::max(hi[c], p[3 * v + c]);
      }
    }
    for (int c = 0; c < 3; ++c) {
      info->add_bbox_min(lo[c]);
      info->add_bbox_max(hi[c]);
    }
  }
  info->set_requested_samples(h.params.requested_samples);
  info->set_seed(h.params.seed);
  info->set_samples_added_by_repair(h.params.samples_added_by_repair);
  info->set_builder_version(ix.builder_version());
  info->set_mapped_bytes(version->mapped_bytes());
  info->set_mesh_hash(h.mesh_hash);
  info->set_report_json(index::IndexReportJson(index::MakeIndexReport(ix)));
  auto* report = info->mutable_build_report();
  const std::string text(ix.report());
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    const size_t eq = line.find('=');
    if (eq == absl::string_view::npos) continue;
    const std::string key(absl::StripAsciiWhitespace(line.substr(0, eq)));
    if (key.empty()) continue;
    (*report)[key] = std::string(absl::StripAsciiWhitespace(line.substr(eq + 1)));
  }
}

// ---------------------------------------------------------------------------
// Options

namespace {

absl::StatusOr<query::NearPairs> NearPairsFor(const ModelConfig& config, int requested,
                                              bool exact_requested) {
  if (!v1::NearPairs_IsValid(requested)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("near_pairs has the unknown value %d", requested));
  }
  if (exact_requested && requested != v1::NEAR_PAIRS_UNSPECIFIED &&
      requested != v1::NEAR_PAIRS_EXACT) {
    return absl::InvalidArgumentError(
        absl::StrFormat("exact_near_pairs contradicts near_pairs = %s",
                        v1::NearPairs_Name(static_cast<v1::NearPairs>(requested))));
  }
  if (exact_requested) return query::NearPairs::kExact;
  switch (static_cast<v1::NearPairs>(requested)) {
    case v1::NEAR_PAIRS_PATH:
      return query::NearPairs::kPath;
    case v1::NEAR_PAIRS_UNFOLD:
      return query::NearPairs::kUnfold;
    case v1::NEAR_PAIRS_EXACT:
      return query::NearPairs::kExact;
    default:
      break;
  }
  if (config.exact_near_pairs()) return query::NearPairs::kExact;
  if (config.unfold_near_pairs()) return query::NearPairs::kUnfold;
  return query::NearPairs::kPath;
}

}  // namespace

DistanceChoice DistanceChoice::Of(const v1::DistanceRequest& r) {
  return {r.near_pairs(), r.exact_near_pairs(), r.tolerance(), r.error_bounds(), r.refine_below()};
}

DistanceChoice DistanceChoice::Of(const v1::DistanceBatch& r) {
  return {r.near_pairs(), r.exact_near_pairs(), r.tolerance(), r.error_bounds(), r.refine_below()};
}

DistanceChoice DistanceChoice::Of(const v1::MatrixRequest& r) {
  return {r.near_pairs(), false, r.tolerance(), r.error_bounds(), r.refine_below()};
}

absl::StatusOr<query::DistanceOptions> DistanceOptionsFor(const ModelConfig& config,
                                                          const DistanceChoice& choice) {
  query::DistanceOptions options;
  GEODEX_ASSIGN_OR_RETURN(options.near_pairs,
                          NearPairsFor(config, choice.near_pairs, choice.exact_near_pairs));
  const double tolerance = choice.tolerance;
  if (!(tolerance >= 0) || !std::isfinite(tolerance)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tolerance must be finite and >= 0, not %g", tolerance));
  }
  options.tolerance = tolerance > 0 ? tolerance : config.tolerance();
  if (!(choice.refine_below >= 0) || !std::isfinite(choice.refine_below)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("refine_below must be finite and >= 0, not %g", choice.refine_below));
  }
  options.refine_below_l1000 = choice.refine_below;
  return options;
}

absl::StatusOr<int32_t> PathCorridorFor(const ModelConfig& config, const v1::PathRequest& request) {
  if (request.exact_corridor() > kMaxPathCorridor) {
    return absl::InvalidArgumentError(absl::StrFormat("exact_corridor %d exceeds %d",
                                                      request.exact_corridor(), kMaxPathCorridor));
  }
  if (request.exact_corridor() > 0) return static_cast<int32_t>(request.exact_corridor());
  return std::clamp<int32_t>(config.exact_path_corridor(), 0, kMaxPathCorridor);
}

}  // namespace geodex::server
