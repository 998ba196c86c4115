#include "tests/soak/soak_client.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/index/index.h"
#include "core/query/exp_map.h"
#include "core/query/input_queries.h"
#include "core/query/engine/query_engine.h"

namespace geodex::soak {

using query::QueryEngine;
using SurfacePoint = mesh::SurfacePoint;

Soak::Soak(std::shared_ptr<grpc::Channel> channel, std::string model,
           std::map<int64_t, std::shared_ptr<const QueryEngine>> engines, int64_t max_pairs)
    : stub_(v1::Geodex::NewStub(channel)),
      model_(std::move(model)),
      engines_(std::move(engines)),
      max_pairs_(max_pairs),
      faces_(engines_.begin()->second->index().num_faces()) {}

void Soak::Run(uint32_t seed, std::chrono::steady_clock::time_point until) {
  std::mt19937 rng(seed);
  while (std::chrono::steady_clock::now() < until) Step(rng);
}

// Draws 0-9: two in ten valid Distance calls, then one each of the invalid
// Distance, StreamDistances, Path, every streamed call in turn and GetModel,
// the rest valid Distance calls again.
void Soak::Step(std::mt19937& rng) {
  const uint32_t kind = rng() % 10;
  const std::vector<StreamedCall>& streamed = StreamedCalls();
  constexpr uint32_t kFirstStreamed = 5;
  if (kind >= kFirstStreamed && kind - kFirstStreamed < streamed.size()) {
    streamed[kind - kFirstStreamed](*this, rng);
    return;
  }
  if (kind == kFirstStreamed + streamed.size()) {
    Model();
    return;
  }
  switch (kind) {
    case 2:
      InvalidDistance(rng);
      break;
    case 3:
      Stream(rng);
      break;
    case 4:
      Path(rng);
      break;
    default:
      ValidDistance(rng);
  }
}

SoakTotals Soak::totals() const {
  return {.valid = valid_.load(), .invalid = invalid_.load(), .violations = violations_.load()};
}

std::vector<SurfacePoint> Soak::Points(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<SurfacePoint> out;
  for (int i = 0; i < n; ++i) {
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    out.push_back({static_cast<int32_t>(rng() % faces_), {a, b, 1 - a - b}});
  }
  return out;
}

v1::SurfacePoints Soak::ToProto(const std::vector<SurfacePoint>& points) {
  v1::SurfacePoints out;
  for (const SurfacePoint& p : points) {
    out.add_faces(p.face);
    for (double w : p.w) out.add_weights(w);
  }
  return out;
}

v1::ModelRef Soak::Ref() const {
  v1::ModelRef ref;
  ref.set_name(model_);
  return ref;
}

std::unique_ptr<grpc::ClientContext> Soak::Context() {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  return context;
}

const QueryEngine* Soak::EngineOf(int64_t version) {
  const auto it = engines_.find(version);
  if (it == engines_.end()) {
    Violation(absl::StrFormat("answered by version %d, which has no reference index", version));
    return nullptr;
  }
  return it->second.get();
}

void Soak::Violation(const std::string& what) {
  if (++violations_ <= 10) {
    std::lock_guard<std::mutex> lock(print_mutex_);
    std::fprintf(stderr, "soak_driver: VIOLATION: %s\n", what.c_str());
  }
}

void Soak::ExpectDistances(const char* call, int64_t version, const std::vector<SurfacePoint>& a,
                           const std::vector<SurfacePoint>& b,
                           const google::protobuf::RepeatedField<double>& got) {
  const QueryEngine* engine = EngineOf(version);
  if (engine == nullptr) return;
  std::vector<double> expected(a.size());
  if (!engine->DistanceBatch(a, b, expected).ok() || got.size() != static_cast<int>(a.size())) {
    Violation(absl::StrFormat("%s: %d answers for %d pairs", call, got.size(), a.size()));
    return;
  }
  for (size_t i = 0; i < a.size(); ++i) {
    if (!(got[i] == expected[i])) {
      Violation(absl::StrFormat("%s: pair %d: %.17g, offline %.17g (version %d)", call, i, got[i],
                                expected[i], version));
      return;
    }
  }
}

void Soak::ValidDistance(std::mt19937& rng) {
  const int n = 1 + static_cast<int>(rng() % 64);
  const auto a = Points(rng, n), b = Points(rng, n);
  v1::DistanceRequest request;
  *request.mutable_model() = Ref();
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  v1::DistanceResponse response;
  const grpc::Status status = stub_->Distance(Context().get(), request, &response);
  ++valid_;
  if (!status.ok()) {
    Violation("Distance: " + status.error_message());
    return;
  }
  ExpectDistances("Distance", response.version(), a, b, response.distances());
}

void Soak::InvalidDistance(std::mt19937& rng) {
  const int n = 4;
  auto a = Points(rng, n), b = Points(rng, n);
  v1::DistanceRequest request;
  grpc::StatusCode expected;
  const int kind = static_cast<int>(rng() % 6);
  switch (kind) {
    case 0:
      a[1].face = faces_ + static_cast<int32_t>(rng() % 1000);
      expected = grpc::StatusCode::OUT_OF_RANGE;
      break;
    case 1:
      b[2].w[0] = std::numeric_limits<double>::quiet_NaN();
      expected = grpc::StatusCode::INVALID_ARGUMENT;
      break;
    case 2:
      a[0].w = {1.5, -0.5, 0};
      expected = grpc::StatusCode::INVALID_ARGUMENT;
      break;
    case 3:
      b.pop_back();
      expected = grpc::StatusCode::INVALID_ARGUMENT;
      break;
    case 4:
      expected = grpc::StatusCode::NOT_FOUND;
      break;
    default:
      a = Points(rng, static_cast<int>(max_pairs_) + 1);
      b = Points(rng, static_cast<int>(max_pairs_) + 1);
      expected = grpc::StatusCode::RESOURCE_EXHAUSTED;
  }
  *request.mutable_model() = Ref();
  if (kind == 4) request.mutable_model()->set_name(model_ + "-no-such-model");
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  v1::DistanceResponse response;
  const grpc::Status status = stub_->Distance(Context().get(), request, &response);
  ++invalid_;
  if (status.error_code() != expected) {
    Violation(absl::StrFormat("invalid Distance (kind %d): code %d '%s', expected %d", kind,
                              status.error_code(), status.error_message(), expected));
  }
}

// Five batches, the third invalid: it alone is refused.
void Soak::Stream(std::mt19937& rng) {
  auto context = Context();
  auto stream = stub_->StreamDistances(context.get());
  std::vector<std::vector<SurfacePoint>> as, bs;
  for (int k = 0; k < 5; ++k) {
    as.push_back(Points(rng, 20));
    bs.push_back(Points(rng, 20));
    v1::DistanceBatch batch;
    batch.set_batch_id(k);
    *batch.mutable_model() = Ref();
    *batch.mutable_a() = ToProto(as.back());
    *batch.mutable_b() = ToProto(bs.back());
    if (k == 2) batch.mutable_a()->set_faces(0, -1);
    if (!stream->Write(batch)) break;
  }
  stream->WritesDone();
  v1::DistanceResult result;
  int answered = 0;
  while (stream->Read(&result)) {
    const int k = static_cast<int>(result.batch_id());
    ++answered;
    if (k == 2) {
      ++invalid_;
      if (result.error_code() != grpc::StatusCode::OUT_OF_RANGE &&
          result.error_code() != grpc::StatusCode::INVALID_ARGUMENT) {
        Violation(absl::StrFormat("stream: bad batch answered with code %d", result.error_code()));
      }
      continue;
    }
    ++valid_;
    if (k < 0 || k >= 5 || result.error_code() != 0) {
      Violation(absl::StrFormat("stream: batch %d: code %d '%s'", k, result.error_code(),
                                result.error_message()));
      continue;
    }
    ExpectDistances("StreamDistances", result.version(), as[k], bs[k], result.distances());
  }
  const grpc::Status status = stream->Finish();
  if (!status.ok() || answered != 5) {
    Violation(absl::StrFormat("stream: %d of 5 batches answered, status '%s'", answered,
                              status.error_message()));
  }
}

void Soak::Path(std::mt19937& rng) {
  const auto a = Points(rng, 2), b = Points(rng, 2);
  v1::PathRequest request;
  *request.mutable_model() = Ref();
  *request.mutable_a() = ToProto(a);
  *request.mutable_b() = ToProto(b);
  v1::PathResponse response;
  const grpc::Status status = stub_->Path(Context().get(), request, &response);
  ++valid_;
  if (!status.ok() || response.paths_size() != 2) {
    Violation("Path: " + status.error_message());
    return;
  }
  const QueryEngine* engine = EngineOf(response.version());
  if (engine == nullptr) return;
  for (int i = 0; i < 2; ++i) {
    auto path = engine->Path(a[i], b[i]);
    if (!path.ok() || response.paths(i).points().faces_size() != static_cast<int>(path->size())) {
      Violation(absl::StrFormat("Path %d: %d points, offline %d", i,
                                response.paths(i).points().faces_size(),
                                path.ok() ? path->size() : 0));
      return;
    }
  }
}

// Opens a server stream with `open` (given the call's context), reads every
// chunk into `take`, then its status, and counts a valid call. Returns the
// version that answered and its engine; no engine (and a violation) when the
// call failed or no reference index has that version.
template <typename Chunk, typename Open, typename Take>
Soak::Answered Soak::ReadStream(const char* call, Open open, Take take) {
  auto context = Context();
  auto reader = open(context.get());
  Chunk chunk;
  Answered answered;
  while (reader->Read(&chunk)) {
    take(chunk);
    answered.version = chunk.version();
  }
  const grpc::Status status = reader->Finish();
  ++valid_;
  if (!status.ok()) {
    Violation(std::string(call) + ": " + status.error_message());
    return answered;
  }
  answered.engine = EngineOf(answered.version);
  return answered;
}

// The lambdas are the class's own code (a static member's), so they reach
// its private helpers.
const std::vector<Soak::StreamedCall>& Soak::StreamedCalls() {
  static const std::vector<StreamedCall> kCalls = {
      // DistanceField from one to three sources: every vertex's distance.
      [](Soak& soak, std::mt19937& rng) {
        const auto sources = soak.Points(rng, 1 + static_cast<int>(rng() % 3));
        v1::DistanceFieldRequest request;
        *request.mutable_model() = soak.Ref();
        *request.mutable_sources() = ToProto(sources);
        std::vector<double> got;
        const Answered answered = soak.ReadStream<v1::DistanceFieldChunk>(
            "DistanceField",
            [&](grpc::ClientContext* c) { return soak.stub_->DistanceField(c, request); },
            [&](const v1::DistanceFieldChunk& chunk) {
              got.insert(got.end(), chunk.distances().begin(), chunk.distances().end());
            });
        if (answered.engine == nullptr) return;
        auto field = answered.engine->Field(sources);
        if (!field.ok() || field->distance != got) {
          soak.Violation(
              absl::StrFormat("DistanceField differs from offline (version %d)", answered.version));
        }
      },
      // ExpMap round one point, radius 0.2-0.8: the vertices and their angles.
      [](Soak& soak, std::mt19937& rng) {
        const auto centre = soak.Points(rng, 1);
        const double radius = 0.2 + 0.6 * std::uniform_real_distribution<double>(0, 1)(rng);
        v1::ExpMapRequest request;
        *request.mutable_model() = soak.Ref();
        *request.mutable_center() = ToProto(centre);
        request.set_radius(radius);
        std::vector<int32_t> vertices;
        std::vector<double> theta;
        const Answered answered = soak.ReadStream<v1::ExpMapChunk>(
            "ExpMap", [&](grpc::ClientContext* c) { return soak.stub_->ExpMap(c, request); },
            [&](const v1::ExpMapChunk& chunk) {
              vertices.insert(vertices.end(), chunk.vertices().begin(), chunk.vertices().end());
              theta.insert(theta.end(), chunk.theta().begin(), chunk.theta().end());
            });
        if (answered.engine == nullptr) return;
        query::ExpMapOptions options;
        options.radius = radius;
        // The engine outlives the call: a non-owning pointer.
        auto queries = query::InputQueries::Create(std::shared_ptr<const query::QueryEngine>(
            answered.engine, [](const query::QueryEngine*) {}));
        query::EnginePoints read;
        absl::StatusOr<std::vector<query::ExpMapVertex>> map =
            queries.ok() && (*queries)->Read(centre, query::Named("center"), &read).ok()
                ? query::ExpMap(**queries, read, 0, options)
                : absl::InternalError("the offline engine refused the centre");
        bool same = map.ok() && map->size() == vertices.size();
        for (size_t i = 0; same && i < vertices.size(); ++i) {
          same = (*map)[i].vertex == vertices[i] && (*map)[i].theta == theta[i];
        }
        if (!same) {
          soak.Violation(
              absl::StrFormat("ExpMap differs from offline (version %d)", answered.version));
        }
      },
  };
  return kCalls;
}

void Soak::Model() {
  v1::GetModelRequest request;
  *request.mutable_model() = Ref();
  v1::ModelInfo info;
  const grpc::Status status = stub_->GetModel(Context().get(), request, &info);
  ++valid_;
  if (!status.ok()) Violation("GetModel: " + status.error_message());
}

}  // namespace geodex::soak
