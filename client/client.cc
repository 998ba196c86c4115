#include "geodex/client/client.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "client/convert.h"
#include "client/grpc_connection.h"
#include "client/retry.h"
#include "client/status_conversion.h"

namespace geodex::client {
namespace {

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
  double refine_below = 0;

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
  batch.set_refine_below(state_->refine_below);
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
                         batch.set_refine_below(query.refine_below);
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
    request.set_refine_below(query.refine_below);
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
  state->refine_below = options.refine_below;
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
