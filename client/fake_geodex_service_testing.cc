#include "client/fake_geodex_service_testing.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace geodex::client::testing {
namespace {

struct Point {
  int32_t face;
  double w[3];
};

// Vertex v of the fake mesh in the lowest face holding it (face f has
// vertices f, f + 1, f + 2 mod 60), weight 1 on it: as the real server reads
// a vertex id.
Point VertexPoint(int32_t v) {
  Point p{std::max(v - 2, 0), {0, 0, 0}};
  p.w[v - p.face] = 1;
  return p;
}

// Validates and unpacks `points`, faces and weights or vertex ids (alone, or
// mixed: geodex.proto's SurfacePoints); `name` ("a", "b", "sources") names
// offending elements as the real server does.
grpc::Status Unpack(const v1::SurfacePoints& points, const char* name, std::vector<Point>* out) {
  const int n = points.vertices_size() > 0 ? points.vertices_size() : points.faces_size();
  const bool faces_given = points.vertices_size() == 0 || points.faces_size() > 0;
  if ((faces_given && points.faces_size() != n) ||
      points.weights_size() != (faces_given ? 3 * n : 0)) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        absl::StrFormat("%s: %d faces, %d weights and %d vertex ids", name,
                                        points.faces_size(), points.weights_size(),
                                        points.vertices_size()));
  }
  out->resize(n);
  for (int i = 0; i < n; ++i) {
    Point& p = (*out)[i];
    if (points.vertices_size() > 0 && (points.vertices(i) >= 0 || !faces_given)) {
      const int32_t v = points.vertices(i);
      if (v < 0 || v >= FakeGeodexService::kNumVertices) {
        return grpc::Status(grpc::StatusCode::OUT_OF_RANGE,
                            absl::StrFormat("%s[%d]: vertex id %d out of range [0, %d)", name, i,
                                            v, FakeGeodexService::kNumVertices));
      }
      p = VertexPoint(v);
      continue;
    }
    p.face = points.faces(i);
    if (p.face < 0 || p.face >= FakeGeodexService::kNumFaces) {
      return grpc::Status(grpc::StatusCode::OUT_OF_RANGE,
                          absl::StrFormat("%s[%d]: face %d is past the end (%d faces)", name, i,
                                          p.face, FakeGeodexService::kNumFaces));
    }
    double sum = 0;
    for (int k = 0; k < 3; ++k) {
      p.w[k] = points.weights(3 * i + k);
      sum += p.w[k];
      if (!(p.w[k] >= -1e-6)) {
        return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                            absl::StrFormat("%s[%d]: negative weight", name, i));
      }
    }
    if (std::abs(sum - 1) > 1e-6) {
      return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                          absl::StrFormat("%s[%d]: weights sum to %g", name, i, sum));
    }
  }
  return grpc::Status::OK;
}

double FakeDistance(const Point& a, const Point& b) {
  double d = std::abs(a.face - b.face);
  for (int k = 0; k < 3; ++k) d += std::abs(a.w[k] - b.w[k]);
  return d;
}

grpc::Status CheckModel(const v1::ModelRef& model) {
  if (model.name() == "fake" && (model.version() == 0 || model.version() == 1)) {
    return grpc::Status::OK;
  }
  if (model.name() == "loading") {
    return grpc::Status(grpc::StatusCode::UNAVAILABLE, "model 'loading' is loading");
  }
  if (model.name() == "fake") {
    return grpc::Status(grpc::StatusCode::NOT_FOUND,
                        absl::StrCat("model 'fake' has no version ", model.version()));
  }
  return grpc::Status(grpc::StatusCode::NOT_FOUND,
                      absl::StrCat("model '", model.name(), "' not found"));
}

grpc::Status Distances(const v1::ModelRef& model, const v1::SurfacePoints& a_points,
                       const v1::SurfacePoints& b_points,
                       google::protobuf::RepeatedField<double>* out) {
  if (grpc::Status s = CheckModel(model); !s.ok()) return s;
  std::vector<Point> a, b;
  if (grpc::Status s = Unpack(a_points, "a", &a); !s.ok()) return s;
  if (grpc::Status s = Unpack(b_points, "b", &b); !s.ok()) return s;
  if (a.size() != b.size()) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        absl::StrFormat("%d points in a but %d in b", a.size(), b.size()));
  }
  for (size_t i = 0; i < a.size(); ++i) out->Add(FakeDistance(a[i], b[i]));
  return grpc::Status::OK;
}

v1::ModelInfo FakeModel() {
  v1::ModelInfo info;
  info.set_name("fake");
  info.set_version(1);
  info.add_available_versions(1);
  info.set_state(v1::ModelInfo::SERVING);
  info.set_num_vertices(FakeGeodexService::kNumVertices);
  info.set_num_faces(FakeGeodexService::kNumFaces);
  info.set_num_samples(FakeGeodexService::kNumSamples);
  info.set_num_triangles(FakeGeodexService::kNumTriangles);
  for (int k = 0; k < 3; ++k) {
    info.add_bbox_min(-1);
    info.add_bbox_max(1);
  }
  (*info.mutable_build_report())["fake"] = "true";
  return info;
}

}  // namespace

grpc::Status FakeGeodexService::Enter(grpc::ServerContext* context) {
  ++calls_;
  absl::Duration delay;
  {
    absl::MutexLock lock(&mu_);
    const auto& metadata = context->client_metadata();
    auto it = metadata.find("authorization");
    last_authorization_ =
        it == metadata.end() ? "" : std::string(it->second.data(), it->second.size());
    delay = delay_;
  }
  if (delay > absl::ZeroDuration()) absl::SleepFor(delay);
  int n = fail_next_.load();
  while (n > 0) {
    if (fail_next_.compare_exchange_weak(n, n - 1)) {
      return grpc::Status(grpc::StatusCode::UNAVAILABLE, "fake: try again");
    }
  }
  return grpc::Status::OK;
}

grpc::Status FakeGeodexService::ListModels(grpc::ServerContext* context,
                                           const v1::ListModelsRequest*,
                                           v1::ListModelsResponse* response) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  *response->add_models() = FakeModel();
  v1::ModelInfo* loading = response->add_models();
  loading->set_name("loading");
  loading->set_state(v1::ModelInfo::LOADING);
  return grpc::Status::OK;
}

grpc::Status FakeGeodexService::GetModel(grpc::ServerContext* context,
                                         const v1::GetModelRequest* request,
                                         v1::ModelInfo* response) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  if (grpc::Status s = CheckModel(request->model()); !s.ok()) return s;
  *response = FakeModel();
  return grpc::Status::OK;
}

grpc::Status FakeGeodexService::Distance(grpc::ServerContext* context,
                                         const v1::DistanceRequest* request,
                                         v1::DistanceResponse* response) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  response->set_version(1);
  return Distances(request->model(), request->a(), request->b(), response->mutable_distances());
}

grpc::Status FakeGeodexService::StreamDistances(
    grpc::ServerContext* context,
    grpc::ServerReaderWriter<v1::DistanceResult, v1::DistanceBatch>* stream) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  v1::DistanceBatch batch;
  v1::ModelRef model;
  bool first = true;
  while (stream->Read(&batch)) {
    if (first) {
      if (batch.model().name().empty()) {
        return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                            "the first batch of a stream must name the model");
      }
      model = batch.model();
      first = false;
    } else if (!batch.model().name().empty()) {
      model = batch.model();
    }
    v1::DistanceResult result;
    result.set_batch_id(batch.batch_id());
    result.set_version(1);
    const grpc::Status s = Distances(model, batch.a(), batch.b(), result.mutable_distances());
    if (!s.ok()) {
      result.clear_distances();
      result.set_error_code(s.error_code());
      result.set_error_message(s.error_message());
    }
    if (!stream->Write(result)) break;
  }
  return grpc::Status::OK;
}

grpc::Status FakeGeodexService::Matrix(grpc::ServerContext* context,
                                       const v1::MatrixRequest* request,
                                       grpc::ServerWriter<v1::MatrixBlock>* writer) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  if (grpc::Status s = CheckModel(request->model()); !s.ok()) return s;
  std::vector<Point> sources, targets;
  if (grpc::Status s = Unpack(request->sources(), "sources", &sources); !s.ok()) return s;
  if (grpc::Status s = Unpack(request->targets(), "targets", &targets); !s.ok()) return s;
  const int64_t block_rows = request->block_rows() > 0 ? request->block_rows() : 2;
  // Last block first: the client must assemble by offset, not by arrival.
  const int64_t num_blocks = (static_cast<int64_t>(sources.size()) + block_rows - 1) / block_rows;
  for (int64_t k = num_blocks - 1; k >= 0; --k) {
    v1::MatrixBlock block;
    const int64_t begin = k * block_rows;
    const int64_t end = std::min<int64_t>(sources.size(), begin + block_rows);
    block.set_row_offset(begin);
    block.set_rows(end - begin);
    block.set_num_targets(targets.size());
    block.set_version(1);
    for (int64_t r = begin; r < end; ++r) {
      for (const Point& t : targets) block.add_values(FakeDistance(sources[r], t));
    }
    if (!writer->Write(block)) break;
  }
  return grpc::Status::OK;
}

grpc::Status FakeGeodexService::Path(grpc::ServerContext* context, const v1::PathRequest* request,
                                     v1::PathResponse* response) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  if (grpc::Status s = CheckModel(request->model()); !s.ok()) return s;
  std::vector<Point> a, b;
  if (grpc::Status s = Unpack(request->a(), "a", &a); !s.ok()) return s;
  if (grpc::Status s = Unpack(request->b(), "b", &b); !s.ok()) return s;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    v1::Polyline* line = response->add_paths();
    for (const Point* p : {&a[i], &b[i]}) {
      line->mutable_points()->add_faces(p->face);
      for (double w : p->w) line->mutable_points()->add_weights(w);
      line->mutable_positions()->add_xyz(p->face);
      line->mutable_positions()->add_xyz(p->w[1]);
      line->mutable_positions()->add_xyz(p->w[2]);
    }
    line->set_length(FakeDistance(a[i], b[i]));
  }
  response->set_version(1);
  return grpc::Status::OK;
}

namespace {

// The field within request.radius(), in the sparse form of the real server.
grpc::Status SparseField(const v1::DistanceFieldRequest& request, const std::vector<Point>& sources,
                         grpc::ServerWriter<v1::DistanceFieldChunk>* writer) {
  const double radius = request.radius();
  if (!(std::isfinite(radius) && radius > 0)) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        absl::StrFormat("the radius must be finite and > 0, got %g", radius));
  }
  std::vector<int32_t> vertices, nearest;
  std::vector<double> distances;
  for (int32_t v = 0; v < FakeGeodexService::kNumVertices; ++v) {
    double best = std::numeric_limits<double>::infinity();
    int32_t near = -1;
    for (size_t s = 0; s < sources.size(); ++s) {
      const double d = std::abs(static_cast<double>(v - sources[s].face));
      if (d < best) best = d, near = static_cast<int32_t>(s);
    }
    if (!(best <= radius)) continue;
    vertices.push_back(v);
    distances.push_back(best);
    nearest.push_back(near);
  }
  const int64_t n = static_cast<int64_t>(vertices.size());
  constexpr int64_t kChunk = 7;
  // At least one chunk, which carries the version of an empty answer.
  for (int64_t begin = 0; begin == 0 || begin < n; begin += kChunk) {
    v1::DistanceFieldChunk chunk;
    chunk.set_vertex_offset(begin);
    chunk.set_num_vertices(n);
    chunk.set_version(1);
    for (int64_t i = begin; i < std::min(n, begin + kChunk); ++i) {
      chunk.add_vertices(vertices[i]);
      chunk.add_distances(distances[i]);
      if (request.with_nearest_source()) chunk.add_nearest_source(nearest[i]);
    }
    if (!writer->Write(chunk)) break;
  }
  return grpc::Status::OK;
}

}  // namespace

grpc::Status FakeGeodexService::DistanceField(grpc::ServerContext* context,
                                              const v1::DistanceFieldRequest* request,
                                              grpc::ServerWriter<v1::DistanceFieldChunk>* writer) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  if (grpc::Status s = CheckModel(request->model()); !s.ok()) return s;
  std::vector<Point> sources;
  if (grpc::Status s = Unpack(request->sources(), "sources", &sources); !s.ok()) return s;
  if (sources.empty()) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "sources: none given");
  }
  constexpr int64_t kChunk = 7;
  if (request->radius() != 0) return SparseField(*request, sources, writer);
  for (int64_t begin = 0; begin < kNumVertices; begin += kChunk) {
    v1::DistanceFieldChunk chunk;
    chunk.set_vertex_offset(begin);
    chunk.set_num_vertices(kNumVertices);
    chunk.set_version(1);
    for (int64_t v = begin; v < std::min(kNumVertices, begin + kChunk); ++v) {
      double best = std::numeric_limits<double>::infinity();
      int32_t nearest = -1;
      for (size_t s = 0; s < sources.size(); ++s) {
        const double d = std::abs(static_cast<double>(v - sources[s].face));
        if (d < best) best = d, nearest = static_cast<int32_t>(s);
      }
      chunk.add_distances(best);
      if (request->with_nearest_source()) chunk.add_nearest_source(nearest);
    }
    if (!writer->Write(chunk)) break;
  }
  return grpc::Status::OK;
}

grpc::Status FakeGeodexService::Locate(grpc::ServerContext* context,
                                       const v1::LocateRequest* request,
                                       v1::LocateResponse* response) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  if (grpc::Status s = CheckModel(request->model()); !s.ok()) return s;
  const auto& xyz = request->positions().xyz();
  if (xyz.size() % 3 != 0) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "positions: not a multiple of 3");
  }
  for (int i = 0; i + 2 < xyz.size(); i += 3) {
    const double x = std::clamp(std::floor(xyz[i]), 0.0, static_cast<double>(kNumFaces - 1));
    response->mutable_points()->add_faces(static_cast<int32_t>(x));
    response->mutable_points()->add_weights(1);
    response->mutable_points()->add_weights(0);
    response->mutable_points()->add_weights(0);
    response->add_distances(std::abs(xyz[i + 1]));
  }
  response->set_version(1);
  return grpc::Status::OK;
}

grpc::Status FakeGeodexService::GetMesh(grpc::ServerContext* context,
                                        const v1::GetMeshRequest* request,
                                        grpc::ServerWriter<v1::MeshChunk>* writer) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  if (grpc::Status s = CheckModel(request->model()); !s.ok()) return s;
  constexpr int64_t kVerticesPerChunk = 7, kFacesPerChunk = 11;
  for (int64_t k = 0; k * kVerticesPerChunk < kNumVertices || k * kFacesPerChunk < kNumFaces; ++k) {
    v1::MeshChunk chunk;
    chunk.set_num_vertices(kNumVertices);
    chunk.set_num_faces(kNumFaces);
    chunk.set_version(1);
    const int64_t v0 = std::min(kNumVertices, k * kVerticesPerChunk);
    const int64_t f0 = std::min(kNumFaces, k * kFacesPerChunk);
    chunk.set_vertex_offset(v0);
    chunk.set_face_offset(f0);
    for (int64_t v = v0; v < std::min(kNumVertices, v0 + kVerticesPerChunk); ++v) {
      chunk.add_positions(v);
      chunk.add_positions(v % 2);
      chunk.add_positions(0);
    }
    for (int64_t f = f0; f < std::min(kNumFaces, f0 + kFacesPerChunk); ++f) {
      for (int64_t c = 0; c < 3; ++c) chunk.add_faces((f + c) % kNumVertices);
    }
    if (!writer->Write(chunk)) break;
  }
  return grpc::Status::OK;
}

// The vertices v with |v - c.face| <= r, at that distance and theta -0.5
// below c.face, 0.5 from it up; 7 entries a chunk.
grpc::Status FakeGeodexService::ExpMap(grpc::ServerContext* context,
                                       const v1::ExpMapRequest* request,
                                       grpc::ServerWriter<v1::ExpMapChunk>* writer) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  if (grpc::Status s = CheckModel(request->model()); !s.ok()) return s;
  std::vector<Point> centre;
  if (grpc::Status s = Unpack(request->center(), "center", &centre); !s.ok()) return s;
  if (centre.size() != 1) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        absl::StrFormat("center: want exactly one point, got %d", centre.size()));
  }
  const double radius = request->radius();
  if (!(std::isfinite(radius) && radius > 0)) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        absl::StrFormat("the radius must be finite and > 0, got %g", radius));
  }
  std::vector<int32_t> vertices;
  for (int32_t v = 0; v < kNumVertices; ++v) {
    if (std::abs(static_cast<double>(v - centre[0].face)) <= radius) vertices.push_back(v);
  }
  const int64_t n = static_cast<int64_t>(vertices.size());
  constexpr int64_t kChunk = 7;
  for (int64_t begin = 0; begin == 0 || begin < n; begin += kChunk) {
    v1::ExpMapChunk chunk;
    chunk.set_num_vertices(n);
    chunk.set_version(1);
    for (int64_t i = begin; i < std::min(n, begin + kChunk); ++i) {
      const int32_t v = vertices[i];
      const double r = std::abs(static_cast<double>(v - centre[0].face));
      const double theta = v < centre[0].face ? -0.5 : 0.5;
      chunk.add_vertices(v);
      chunk.add_r(r);
      chunk.add_theta(theta);
      chunk.add_u(r * std::cos(theta));
      chunk.add_v(r * std::sin(theta));
    }
    if (!writer->Write(chunk)) break;
  }
  return grpc::Status::OK;
}

grpc::Status FakeGeodexService::GetTriangulation(grpc::ServerContext* context,
                                                 const v1::GetTriangulationRequest* request,
                                                 v1::TriangulationResponse* response) {
  if (grpc::Status s = Enter(context); !s.ok()) return s;
  if (grpc::Status s = CheckModel(request->model()); !s.ok()) return s;
  response->set_version(1);
  response->set_num_vertices(kNumVertices);
  for (int32_t i = 0; i < kNumSamples; ++i) {
    const int32_t v = 6 * i;
    response->add_sample_vertices(v);
    for (double x : {static_cast<double>(v), static_cast<double>(v % 2), 0.0}) {
      response->mutable_sample_positions()->add_xyz(x);
    }
    const Point p = VertexPoint(v);
    response->mutable_sample_points()->add_faces(p.face);
    for (double w : p.w) response->mutable_sample_points()->add_weights(w);
  }
  for (int32_t t = 0; t < kNumTriangles; ++t) {
    for (int32_t k = 0; k < 3; ++k) {
      response->add_triangle_corners((t + k) % kNumSamples);
      response->add_triangle_neighbors(k == 0 ? (t + 1) % kNumTriangles : -1);
    }
  }
  for (int32_t v = 0; v < kNumVertices; ++v) response->add_vertex_triangles(v % kNumTriangles);
  return grpc::Status::OK;
}

FakeGeodexServer::FakeGeodexServer() {
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(&service_);
  server_ = builder.BuildAndStart();
  address_ = absl::StrCat("127.0.0.1:", port);
}

FakeGeodexServer::~FakeGeodexServer() {
  server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
}

}  // namespace geodex::client::testing
