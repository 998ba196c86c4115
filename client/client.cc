#include "geodex/client/client.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "client/grpc_connection.h"
#include "client/retry.h"
#include "client/status_conversion.h"

namespace geodex::client {
namespace {

v1::ModelRef ToProto(const ModelRef& model) {
  v1::ModelRef ref;
  ref.set_name(model.name);
  ref.set_version(model.version);
  return ref;
}

void AppendPoint(const SurfacePoint& p, v1::SurfacePoints* out) {
  out->add_faces(p.face);
  out->add_weights(p.w[0]);
  out->add_weights(p.w[1]);
  out->add_weights(p.w[2]);
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
  out.mutable_faces()->Reserve(points.size());
  out.mutable_weights()->Reserve(3 * points.size());
  for (const SurfacePoint& p : points) AppendPoint(p, &out);
  return out;
}

// Pairs [begin, end) as the packed arrays a and b.
void PairsToProto(absl::Span<const PointPair> pairs, size_t begin, size_t end, v1::SurfacePoints* a,
                  v1::SurfacePoints* b) {
  const int n = static_cast<int>(end - begin);
  a->mutable_faces()->Reserve(n);
  a->mutable_weights()->Reserve(3 * n);
  b->mutable_faces()->Reserve(n);
  b->mutable_weights()->Reserve(3 * n);
  for (size_t i = begin; i < end; ++i) {
    AppendPoint(pairs[i].a, a);
    AppendPoint(pairs[i].b, b);
  }
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

// `status` with "pairs [begin, end): " before its message.
absl::Status InPairs(const absl::Status& status, size_t begin, size_t end) {
  return absl::Status(status.code(), absl::StrFormat("pairs [%d, %d): %s", begin, end,
                                                     std::string(status.message())));
}

// Cancels and joins a writer thread on every way out of the reading scope.
class WriterGuard {
 public:
  WriterGuard(DistanceStream& stream, std::thread thread)
      : stream_(stream), thread_(std::move(thread)) {}
  ~WriterGuard() {
    if (thread_.joinable()) {
      stream_.Cancel();
      thread_.join();
    }
  }
  void Join() { thread_.join(); }

 private:
  DistanceStream& stream_;
  std::thread thread_;
};

}  // namespace

const char* StateName(ModelInfo::State state) {
  switch (state) {
    case ModelInfo::State::kLoading:
      return "LOADING";
    case ModelInfo::State::kServing:
      return "SERVING";
    case ModelInfo::State::kFailed:
      return "FAILED";
    default:
      return "STATE_UNSPECIFIED";
  }
}

// ---------------------------------------------------------------------------
// DistanceSession

struct DistanceSession::State {
  std::unique_ptr<DistanceStream> stream;
  v1::ModelRef model;
  v1::NearPairs near_pairs = v1::NEAR_PAIRS_UNSPECIFIED;

  absl::Mutex write_mu;
  uint64_t next_id ABSL_GUARDED_BY(write_mu) = 0;
  bool send_closed ABSL_GUARDED_BY(write_mu) = false;
  bool broken ABSL_GUARDED_BY(write_mu) = false;

  absl::Mutex read_mu;
  bool finished = false;
};

DistanceSession::DistanceSession(std::unique_ptr<State> state) : state_(std::move(state)) {}
DistanceSession::DistanceSession(DistanceSession&&) noexcept = default;
DistanceSession& DistanceSession::operator=(DistanceSession&&) noexcept = default;

DistanceSession::~DistanceSession() {
  if (state_ != nullptr && !state_->finished) state_->stream->Cancel();
}

absl::StatusOr<uint64_t> DistanceSession::Send(absl::Span<const PointPair> pairs) {
  if (pairs.empty()) return absl::InvalidArgumentError("a batch needs at least one pair");
  absl::MutexLock lock(&state_->write_mu);
  if (state_->send_closed) {
    return absl::FailedPreconditionError("Send after CloseSend on a distance session");
  }
  if (state_->broken) {
    return absl::UnavailableError("the distance stream is broken; Finish() says why");
  }
  v1::DistanceBatch batch;
  const uint64_t id = state_->next_id;
  batch.set_batch_id(id);
  // Only the first batch names the model; the server keeps it for the stream.
  if (id == 0) *batch.mutable_model() = state_->model;
  batch.set_near_pairs(state_->near_pairs);
  PairsToProto(pairs, 0, pairs.size(), batch.mutable_a(), batch.mutable_b());
  if (!state_->stream->Write(batch)) {
    state_->broken = true;
    return absl::UnavailableError("the distance stream is broken; Finish() says why");
  }
  ++state_->next_id;
  return id;
}

void DistanceSession::CloseSend() {
  absl::MutexLock lock(&state_->write_mu);
  if (state_->send_closed) return;
  state_->send_closed = true;
  if (!state_->broken) state_->stream->WritesDone();
}

std::optional<DistanceBatchResult> DistanceSession::Read() {
  absl::MutexLock lock(&state_->read_mu);
  v1::DistanceResult result;
  if (!state_->stream->Read(&result)) return std::nullopt;
  DistanceBatchResult out;
  out.batch_id = result.batch_id();
  out.status = FromWireCode(result.error_code(), result.error_message());
  out.distances.assign(result.distances().begin(), result.distances().end());
  out.version = result.version();
  return out;
}

void DistanceSession::Cancel() { state_->stream->Cancel(); }

absl::Status DistanceSession::Finish() {
  if (state_->finished) {
    return absl::FailedPreconditionError("Finish called twice on a distance session");
  }
  state_->finished = true;
  return state_->stream->Finish();
}

// ---------------------------------------------------------------------------
// Client

Client::Client(std::shared_ptr<GeodexConnection> connection, ClientOptions options)
    : connection_(std::move(connection)), options_(options) {
  options_.batch_size = std::max(1, options_.batch_size);
  options_.path_batch_size = std::max(1, options_.path_batch_size);
  options_.locate_batch_size = std::max(1, options_.locate_batch_size);
  options_.retry.max_attempts = std::max(1, options_.retry.max_attempts);
}

absl::StatusOr<std::vector<ModelInfo>> Client::ListModels() const {
  absl::StatusOr<v1::ListModelsResponse> response = connection_->ListModels({});
  if (!response.ok()) return response.status();
  std::vector<ModelInfo> models;
  models.reserve(response->models_size());
  for (const v1::ModelInfo& m : response->models()) models.push_back(FromProto(m));
  return models;
}

absl::StatusOr<ModelInfo> Client::GetModel(const ModelRef& model) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  v1::GetModelRequest request;
  *request.mutable_model() = ToProto(model);
  absl::StatusOr<v1::ModelInfo> response = connection_->GetModel(request);
  if (!response.ok()) return response.status();
  return FromProto(*response);
}

namespace {

// One StreamDistances attempt for batches [*next_batch, num_batches) of
// `pairs`; advances *next_batch past every batch answered, writing the
// answers into `out`.
absl::Status StreamDistancesOnce(GeodexConnection& connection, const v1::ModelRef& model,
                                 absl::Span<const PointPair> pairs, const DistanceQuery& query,
                                 size_t batch_size, uint64_t* next_batch, Distances* out) {
  const uint64_t num_batches = (pairs.size() + batch_size - 1) / batch_size;
  const uint64_t first = *next_batch;
  std::unique_ptr<DistanceStream> stream = connection.StreamDistances(StreamOptions{});

  // The writer runs ahead of the reader; gRPC flow control bounds how far.
  // Reading on this thread while another writes is what keeps a large call
  // from deadlocking on full buffers in both directions.
  WriterGuard writer(*stream,
                     std::thread([&stream, &model, pairs, &query, batch_size, first, num_batches] {
                       for (uint64_t k = first; k < num_batches; ++k) {
                         v1::DistanceBatch batch;
                         batch.set_batch_id(k);
                         if (k == first) *batch.mutable_model() = model;
                         batch.set_near_pairs(ToProto(query.near_pairs));
                         batch.set_tolerance(query.tolerance);
                         batch.set_error_bounds(query.error_bounds);
                         const size_t begin = k * batch_size;
                         const size_t end = std::min(pairs.size(), begin + batch_size);
                         PairsToProto(pairs, begin, end, batch.mutable_a(), batch.mutable_b());
                         if (!stream->Write(batch)) return;  // broken: the reader finds out why
                       }
                       stream->WritesDone();
                     }));

  absl::Status batch_error;
  v1::DistanceResult result;
  while (stream->Read(&result)) {
    const uint64_t k = *next_batch;
    const size_t begin = k * batch_size;
    const size_t end = std::min(pairs.size(), begin + batch_size);
    if (result.batch_id() != k) {
      batch_error = absl::DataLossError(absl::StrFormat(
          "the server answered batch %d when batch %d was due", result.batch_id(), k));
    } else if (result.error_code() != 0) {
      batch_error = InPairs(FromWireCode(result.error_code(), result.error_message()), begin, end);
    } else if (result.distances_size() != static_cast<int>(end - begin)) {
      batch_error =
          InPairs(absl::DataLossError(absl::StrFormat("the server sent %d distances for %d pairs",
                                                      result.distances_size(), end - begin)),
                  begin, end);
    } else if (query.error_bounds && result.bounds_size() != static_cast<int>(end - begin)) {
      batch_error =
          InPairs(absl::DataLossError(absl::StrFormat("the server sent %d bounds for %d pairs",
                                                      result.bounds_size(), end - begin)),
                  begin, end);
    }
    if (!batch_error.ok()) {
      stream->Cancel();
      break;
    }
    std::copy(result.distances().begin(), result.distances().end(), out->distance.begin() + begin);
    if (query.error_bounds) {
      std::copy(result.bounds().begin(), result.bounds().end(), out->bound.begin() + begin);
    }
    *next_batch = k + 1;
  }
  writer.Join();
  const absl::Status status = stream->Finish();
  if (!batch_error.ok()) return batch_error;
  if (!status.ok()) return status;
  if (*next_batch != num_batches) {
    return absl::DataLossError(absl::StrFormat("the distance stream ended after %d of %d batches",
                                               *next_batch, num_batches));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::vector<double>> Client::Distance(const ModelRef& model,
                                                     absl::Span<const PointPair> pairs,
                                                     NearPairs near_pairs) const {
  absl::StatusOr<Distances> d = Distance(model, pairs, DistanceQuery{.near_pairs = near_pairs});
  if (!d.ok()) return d.status();
  return std::move(d->distance);
}

absl::StatusOr<Distances> Client::Distance(const ModelRef& model, absl::Span<const PointPair> pairs,
                                           const DistanceQuery& query) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  if (pairs.empty()) return Distances{};
  const size_t batch_size = options_.batch_size;

  if (pairs.size() <= batch_size) {
    // One batch: a unary call costs one round trip and no thread.
    v1::DistanceRequest request;
    *request.mutable_model() = ToProto(model);
    request.set_near_pairs(ToProto(query.near_pairs));
    request.set_tolerance(query.tolerance);
    request.set_error_bounds(query.error_bounds);
    PairsToProto(pairs, 0, pairs.size(), request.mutable_a(), request.mutable_b());
    absl::StatusOr<v1::DistanceResponse> response = connection_->Distance(request);
    if (!response.ok()) return response.status();
    if (response->distances_size() != static_cast<int>(pairs.size()) ||
        (query.error_bounds && response->bounds_size() != static_cast<int>(pairs.size()))) {
      return absl::DataLossError(
          absl::StrFormat("the server sent %d distances and %d bounds for %d pairs",
                          response->distances_size(), response->bounds_size(), pairs.size()));
    }
    Distances out;
    out.distance.assign(response->distances().begin(), response->distances().end());
    if (query.error_bounds) out.bound.assign(response->bounds().begin(), response->bounds().end());
    return out;
  }

  Distances out;
  out.distance.assign(pairs.size(), std::numeric_limits<double>::quiet_NaN());
  if (query.error_bounds) out.bound.assign(pairs.size(), std::numeric_limits<double>::quiet_NaN());
  const v1::ModelRef ref = ToProto(model);
  uint64_t next_batch = 0;
  int failures = 0;  // consecutive failed attempts without progress
  while (true) {
    const uint64_t before = next_batch;
    const absl::Status status =
        StreamDistancesOnce(*connection_, ref, pairs, query, batch_size, &next_batch, &out);
    if (status.ok()) return out;
    if (next_batch > before) failures = 0;  // a stream that made progress is not a repeat
    ++failures;
    if (!IsRetryable(options_.retry, status)) return status;
    if (failures >= options_.retry.max_attempts) return GaveUp(status, failures);
    absl::SleepFor(BackoffDelay(options_.retry, failures));
  }
}

DistanceSession Client::OpenDistanceSession(const ModelRef& model, SessionOptions options) const {
  auto state = std::make_unique<DistanceSession::State>();
  StreamOptions stream_options;
  stream_options.deadline = options.deadline;
  state->stream = connection_->StreamDistances(stream_options);
  state->model = ToProto(model);
  state->near_pairs = ToProto(options.near_pairs);
  return DistanceSession(std::move(state));
}

absl::StatusOr<DistanceMatrix> Client::Matrix(const ModelRef& model,
                                              absl::Span<const SurfacePoint> sources,
                                              absl::Span<const SurfacePoint> targets,
                                              NearPairs near_pairs) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  DistanceMatrix matrix;
  matrix.rows = static_cast<int64_t>(sources.size());
  matrix.cols = static_cast<int64_t>(targets.size());
  if (sources.empty() || targets.empty()) return matrix;

  v1::MatrixRequest request;
  *request.mutable_model() = ToProto(model);
  *request.mutable_sources() = ToProto(sources);
  *request.mutable_targets() = ToProto(targets);
  request.set_near_pairs(ToProto(near_pairs));
  absl::StatusOr<std::vector<v1::MatrixBlock>> blocks = connection_->Matrix(request);
  if (!blocks.ok()) return blocks.status();

  matrix.values.assign(matrix.rows * matrix.cols, std::numeric_limits<double>::quiet_NaN());
  std::vector<bool> row_seen(matrix.rows, false);
  int64_t rows_seen = 0;
  for (const v1::MatrixBlock& block : *blocks) {
    const int64_t offset = block.row_offset();
    const int64_t rows = block.rows();
    if (block.num_targets() != matrix.cols || offset < 0 || rows < 0 ||
        offset + rows > matrix.rows || block.values_size() != rows * matrix.cols) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent a matrix block of rows [%d, %d) x %d targets with %d values for a "
          "%d x %d matrix",
          offset, offset + rows, block.num_targets(), block.values_size(), matrix.rows,
          matrix.cols));
    }
    for (int64_t r = offset; r < offset + rows; ++r) {
      if (row_seen[r]) {
        return absl::DataLossError(absl::StrFormat("the server sent matrix row %d twice", r));
      }
      row_seen[r] = true;
    }
    rows_seen += rows;
    std::copy(block.values().begin(), block.values().end(),
              matrix.values.begin() + offset * matrix.cols);
    matrix.version = block.version();
  }
  if (rows_seen != matrix.rows) {
    return absl::DataLossError(
        absl::StrFormat("the server sent %d of %d matrix rows", rows_seen, matrix.rows));
  }
  return matrix;
}

absl::StatusOr<std::vector<GeodesicPath>> Client::Path(const ModelRef& model,
                                                       absl::Span<const PointPair> pairs,
                                                       uint32_t exact_corridor) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  std::vector<GeodesicPath> paths;
  paths.reserve(pairs.size());
  const size_t chunk = options_.path_batch_size;
  for (size_t begin = 0; begin < pairs.size(); begin += chunk) {
    const size_t end = std::min(pairs.size(), begin + chunk);
    v1::PathRequest request;
    *request.mutable_model() = ToProto(model);
    PairsToProto(pairs, begin, end, request.mutable_a(), request.mutable_b());
    request.set_exact_corridor(exact_corridor);
    absl::StatusOr<v1::PathResponse> response = connection_->Path(request);
    if (!response.ok()) {
      return pairs.size() > chunk ? InPairs(response.status(), begin, end) : response.status();
    }
    if (response->paths_size() != static_cast<int>(end - begin)) {
      return absl::DataLossError(absl::StrFormat("the server sent %d paths for %d pairs",
                                                 response->paths_size(), end - begin));
    }
    for (const v1::Polyline& polyline : response->paths()) {
      GeodesicPath path;
      absl::StatusOr<std::vector<SurfacePoint>> points = FromProto(polyline.points());
      if (!points.ok()) return points.status();
      path.points = *std::move(points);
      const auto& xyz = polyline.positions().xyz();
      if (xyz.size() != 3 * static_cast<int>(path.points.size())) {
        return absl::DataLossError(
            absl::StrFormat("the server sent a path of %d points with %d coordinates",
                            path.points.size(), xyz.size()));
      }
      path.positions.resize(path.points.size());
      for (size_t i = 0; i < path.points.size(); ++i) {
        path.positions[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
      }
      path.length = polyline.length();
      paths.push_back(std::move(path));
    }
  }
  return paths;
}

absl::StatusOr<VertexDistances> Client::DistanceField(const ModelRef& model,
                                                      absl::Span<const SurfacePoint> sources,
                                                      bool with_nearest_source) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  v1::DistanceFieldRequest request;
  *request.mutable_model() = ToProto(model);
  *request.mutable_sources() = ToProto(sources);
  request.set_with_nearest_source(with_nearest_source);
  absl::StatusOr<std::vector<v1::DistanceFieldChunk>> chunks = connection_->DistanceField(request);
  if (!chunks.ok()) return chunks.status();

  VertexDistances field;
  const int64_t n = chunks->empty() ? 0 : chunks->front().num_vertices();
  field.distances.assign(n, std::numeric_limits<double>::quiet_NaN());
  if (with_nearest_source) field.nearest_source.assign(n, -1);
  std::vector<bool> seen(n, false);
  int64_t covered = 0;
  for (const v1::DistanceFieldChunk& chunk : *chunks) {
    const int64_t offset = chunk.vertex_offset();
    const int64_t size = chunk.distances_size();
    if (chunk.num_vertices() != n || offset < 0 || offset + size > n ||
        (with_nearest_source && chunk.nearest_source_size() != size)) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent a distance field chunk of vertices [%d, %d) of %d (%d nearest "
          "sources) for a field of %d vertices",
          offset, offset + size, chunk.num_vertices(), chunk.nearest_source_size(), n));
    }
    for (int64_t v = offset; v < offset + size; ++v) {
      if (seen[v]) {
        return absl::DataLossError(
            absl::StrFormat("the server sent the distance of vertex %d twice", v));
      }
      seen[v] = true;
    }
    covered += size;
    std::copy(chunk.distances().begin(), chunk.distances().end(), field.distances.begin() + offset);
    if (with_nearest_source) {
      std::copy(chunk.nearest_source().begin(), chunk.nearest_source().end(),
                field.nearest_source.begin() + offset);
    }
    field.version = chunk.version();
  }
  if (covered != n) {
    return absl::DataLossError(
        absl::StrFormat("the server sent distances for %d of %d vertices", covered, n));
  }
  return field;
}

absl::StatusOr<VertexDistancesWithin> Client::DistanceFieldWithin(
    const ModelRef& model, absl::Span<const SurfacePoint> sources,
    const FieldWithinQuery& query) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  if (!(std::isfinite(query.radius) && query.radius > 0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the radius must be finite and > 0, got %g", query.radius));
  }
  v1::DistanceFieldRequest request;
  *request.mutable_model() = ToProto(model);
  *request.mutable_sources() = ToProto(sources);
  request.set_with_nearest_source(query.with_nearest_source);
  request.set_radius(query.radius);
  absl::StatusOr<std::vector<v1::DistanceFieldChunk>> chunks = connection_->DistanceField(request);
  if (!chunks.ok()) return chunks.status();

  VertexDistancesWithin field;
  const int64_t n = chunks->empty() ? 0 : chunks->front().num_vertices();
  for (const v1::DistanceFieldChunk& chunk : *chunks) {
    const int size = chunk.distances_size();
    if (chunk.vertices_size() != size) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent a distance field chunk of %d distances for %d vertices%s", size,
          chunk.vertices_size(),
          chunk.vertices_size() == 0 ? " (a whole-mesh field: the server predates radius fields)"
                                     : ""));
    }
    if (chunk.num_vertices() != n || chunk.vertex_offset() != std::ssize(field.vertices) ||
        std::ssize(field.vertices) + size > n ||
        (query.with_nearest_source && chunk.nearest_source_size() != size)) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent a chunk of entries [%d, %d) of %d (%d nearest sources), after %d, for a "
          "field of %d vertices within the radius",
          chunk.vertex_offset(), chunk.vertex_offset() + size, chunk.num_vertices(),
          chunk.nearest_source_size(), field.vertices.size(), n));
    }
    for (int i = 0; i < size; ++i) {
      if (!field.vertices.empty() && chunk.vertices(i) <= field.vertices.back()) {
        return absl::DataLossError(
            absl::StrFormat("the server sent field vertices out of order (%d after %d)",
                            chunk.vertices(i), field.vertices.back()));
      }
      field.vertices.push_back(chunk.vertices(i));
    }
    field.distances.insert(field.distances.end(), chunk.distances().begin(),
                           chunk.distances().end());
    if (query.with_nearest_source) {
      field.nearest_source.insert(field.nearest_source.end(), chunk.nearest_source().begin(),
                                  chunk.nearest_source().end());
    }
    field.version = chunk.version();
  }
  if (std::ssize(field.vertices) != n) {
    return absl::DataLossError(
        absl::StrFormat("the server sent %d of the field's %d vertices within the radius",
                        field.vertices.size(), n));
  }
  return field;
}

absl::StatusOr<client::ExpMap> Client::ExpMap(const ModelRef& model, const SurfacePoint& center,
                                              const ExpMapQuery& query) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  if (!(std::isfinite(query.radius) && query.radius > 0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the radius must be finite and > 0, got %g", query.radius));
  }
  v1::ExpMapRequest request;
  *request.mutable_model() = ToProto(model);
  *request.mutable_center() = ToProto(absl::Span<const SurfacePoint>(&center, 1));
  request.set_radius(query.radius);
  if (query.reference_direction) {
    request.mutable_reference_direction()->mutable_xyz()->Assign(query.reference_direction->begin(),
                                                                 query.reference_direction->end());
  }
  request.set_near_pairs(ToProto(query.near_pairs));
  request.set_tolerance(query.tolerance);
  absl::StatusOr<std::vector<v1::ExpMapChunk>> chunks = connection_->ExpMap(request);
  if (!chunks.ok()) return chunks.status();

  client::ExpMap map;
  const int64_t n = chunks->empty() ? 0 : chunks->front().num_vertices();
  for (const v1::ExpMapChunk& chunk : *chunks) {
    const int size = chunk.vertices_size();
    if (chunk.num_vertices() != n || chunk.r_size() != size || chunk.theta_size() != size ||
        chunk.u_size() != size || chunk.v_size() != size ||
        static_cast<int64_t>(map.vertices.size()) + size > n) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent an exponential map chunk of %d vertices (%d r, %d theta, %d u, %d v) "
          "of %d, after %d, for a map of %d",
          size, chunk.r_size(), chunk.theta_size(), chunk.u_size(), chunk.v_size(),
          chunk.num_vertices(), map.vertices.size(), n));
    }
    for (int i = 0; i < size; ++i) {
      if (!map.vertices.empty() && chunk.vertices(i) <= map.vertices.back()) {
        return absl::DataLossError(
            absl::StrFormat("the server sent exponential map vertices out of order (%d after %d)",
                            chunk.vertices(i), map.vertices.back()));
      }
      map.vertices.push_back(chunk.vertices(i));
    }
    map.r.insert(map.r.end(), chunk.r().begin(), chunk.r().end());
    map.theta.insert(map.theta.end(), chunk.theta().begin(), chunk.theta().end());
    map.u.insert(map.u.end(), chunk.u().begin(), chunk.u().end());
    map.v.insert(map.v.end(), chunk.v().begin(), chunk.v().end());
    map.version = chunk.version();
  }
  if (static_cast<int64_t>(map.vertices.size()) != n) {
    return absl::DataLossError(absl::StrFormat(
        "the server sent %d of the exponential map's %d vertices", map.vertices.size(), n));
  }
  return map;
}

absl::StatusOr<std::vector<LocatedPoint>> Client::Locate(
    const ModelRef& model, absl::Span<const Position> positions) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  std::vector<LocatedPoint> located;
  located.reserve(positions.size());
  const size_t chunk = options_.locate_batch_size;
  for (size_t begin = 0; begin < positions.size(); begin += chunk) {
    const size_t end = std::min(positions.size(), begin + chunk);
    v1::LocateRequest request;
    *request.mutable_model() = ToProto(model);
    auto* xyz = request.mutable_positions()->mutable_xyz();
    xyz->Reserve(3 * (end - begin));
    for (size_t i = begin; i < end; ++i) {
      for (double c : positions[i]) xyz->Add(c);
    }
    absl::StatusOr<v1::LocateResponse> response = connection_->Locate(request);
    if (!response.ok()) return response.status();
    absl::StatusOr<std::vector<SurfacePoint>> points = FromProto(response->points());
    if (!points.ok()) return points.status();
    if (points->size() != end - begin ||
        response->distances_size() != static_cast<int>(end - begin)) {
      return absl::DataLossError(
          absl::StrFormat("the server located %d points (%d distances) of %d", points->size(),
                          response->distances_size(), end - begin));
    }
    for (size_t i = 0; i < points->size(); ++i) {
      located.push_back({(*points)[i], response->distances(i)});
    }
  }
  return located;
}

absl::StatusOr<Mesh> Client::GetMesh(const ModelRef& model) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  v1::GetMeshRequest request;
  *request.mutable_model() = ToProto(model);
  absl::StatusOr<std::vector<v1::MeshChunk>> chunks = connection_->GetMesh(request);
  if (!chunks.ok()) return chunks.status();
  if (chunks->empty()) return absl::DataLossError("the server sent no mesh chunks");

  const v1::MeshChunk& first = chunks->front();
  const uint64_t num_vertices = first.num_vertices();
  const uint64_t num_faces = first.num_faces();
  const int64_t version = first.version();
  if (model.version != 0 && version != model.version) {
    return absl::DataLossError(
        absl::StrFormat("the server sent the mesh of version %d when version %d was asked for",
                        version, model.version));
  }
  // The ranges are checked before anything is allocated: the totals are only
  // the server's word until the chunks add up to them.
  uint64_t next_vertex = 0, next_face = 0;
  for (size_t k = 0; k < chunks->size(); ++k) {
    const v1::MeshChunk& chunk = (*chunks)[k];
    if (chunk.num_vertices() != num_vertices || chunk.num_faces() != num_faces ||
        chunk.version() != version) {
      return absl::DataLossError(absl::StrFormat(
          "mesh chunk %d is of a mesh of %d vertices and %d faces, version %d; chunk 0 of one of "
          "%d vertices and %d faces, version %d",
          k, chunk.num_vertices(), chunk.num_faces(), chunk.version(), num_vertices, num_faces,
          version));
    }
    if (chunk.positions_size() % 3 != 0 || chunk.faces_size() % 3 != 0) {
      return absl::DataLossError(absl::StrFormat(
          "mesh chunk %d has %d coordinates and %d face vertex ids; both must be multiples of 3", k,
          chunk.positions_size(), chunk.faces_size()));
    }
    if (chunk.vertex_offset() != next_vertex || chunk.face_offset() != next_face) {
      return absl::DataLossError(absl::StrFormat(
          "mesh chunk %d starts at vertex %d and face %d, not at vertex %d and face %d where the "
          "chunks before it stopped",
          k, chunk.vertex_offset(), chunk.face_offset(), next_vertex, next_face));
    }
    next_vertex += chunk.positions_size() / 3;
    next_face += chunk.faces_size() / 3;
    if (next_vertex > num_vertices || next_face > num_faces) {
      return absl::DataLossError(absl::StrFormat(
          "mesh chunk %d goes past the end of the mesh: to vertex %d of %d and face %d of %d", k,
          next_vertex, num_vertices, next_face, num_faces));
    }
  }
  if (next_vertex != num_vertices || next_face != num_faces) {
    return absl::DataLossError(
        absl::StrFormat("the server sent %d of %d mesh vertices and %d of %d faces", next_vertex,
                        num_vertices, next_face, num_faces));
  }

  Mesh mesh;
  mesh.version = version;
  mesh.positions.reserve(num_vertices);
  mesh.faces.reserve(num_faces);
  for (const v1::MeshChunk& chunk : *chunks) {
    const auto& xyz = chunk.positions();
    for (int i = 0; i < xyz.size(); i += 3) {
      mesh.positions.push_back({xyz[i], xyz[i + 1], xyz[i + 2]});
    }
    const auto& ids = chunk.faces();
    for (int i = 0; i < ids.size(); i += 3) {
      for (int c = 0; c < 3; ++c) {
        if (ids[i + c] >= num_vertices) {
          return absl::DataLossError(
              absl::StrFormat("mesh face %d names vertex %d, past the end (%d vertices)",
                              mesh.faces.size(), ids[i + c], num_vertices));
        }
      }
      mesh.faces.push_back({ids[i], ids[i + 1], ids[i + 2]});
    }
  }
  return mesh;
}

// ---------------------------------------------------------------------------
// Connect

absl::StatusOr<std::shared_ptr<GeodexConnection>> MakeGrpcConnection(
    const std::string& target, const ConnectOptions& options) {
  absl::StatusOr<std::shared_ptr<GeodexConnection>> connection =
      MakeGrpcConnectionNoRetry(target, options);
  if (!connection.ok()) return connection.status();
  return MakeRetryingConnection(*std::move(connection), options.retry);
}

absl::StatusOr<Client> Connect(const std::string& target, const ConnectOptions& options) {
  absl::StatusOr<std::shared_ptr<GeodexConnection>> connection =
      MakeGrpcConnection(target, options);
  if (!connection.ok()) return connection.status();
  ClientOptions client_options;
  client_options.batch_size = options.batch_size;
  client_options.retry = options.retry;
  return Client(*std::move(connection), client_options);
}

}  // namespace geodex::client
