// soak_driver: many concurrent clients of one geodex-server, for
// tests/soak/soak.sh. Each thread sends a random mix of valid requests
// (Distance, StreamDistances, Path, DistanceField, ExpMap, GetModel) and
// invalid ones (faces past the end, NaN and negative weights, wrong lengths,
// an unknown model, too many pairs, a bad batch inside a good stream) until
// the time is up. Every valid answer is compared, to the bit, with the
// offline engine of the version that answered it (--version V=INDEX); every
// invalid request must be refused with its code while the rest of the call
// (the other batches of a stream) is answered.
//
//   soak_driver --server ADDR --model M --version 1=v1.gdx --version 2=v2.gdx
//               [--threads 8] [--seconds 30] [--max-pairs 1000]
//
// Prints one line of counts; exits 1 on any violation (the first few are
// printed), 2 on bad usage.

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/strings/str_format.h"
#include "core/index/index.h"
#include "core/query/internal/exp_map.h"
#include "core/query/internal/query_engine.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "grpcpp/create_channel.h"

namespace geodex {
namespace {

using query::QueryEngine;
using SurfacePoint = mesh::SurfacePoint;

struct Counts {
  std::atomic<int64_t> valid{0}, invalid{0}, violations{0};
};

class Soak {
 public:
  Soak(std::shared_ptr<grpc::Channel> channel, std::string model,
       std::map<int64_t, std::shared_ptr<const QueryEngine>> engines, int64_t max_pairs)
      : stub_(v1::Geodex::NewStub(channel)),
        model_(std::move(model)),
        engines_(std::move(engines)),
        max_pairs_(max_pairs),
        faces_(engines_.begin()->second->index().num_faces()) {}

  void Run(uint32_t seed, std::chrono::steady_clock::time_point until) {
    std::mt19937 rng(seed);
    while (std::chrono::steady_clock::now() < until) {
      switch (rng() % 10) {
        case 0:
        case 1:
          ValidDistance(rng);
          break;
        case 2:
          InvalidDistance(rng);
          break;
        case 3:
          Stream(rng);
          break;
        case 4:
          Path(rng);
          break;
        case 5:
          Field(rng);
          break;
        case 6:
          ExpMap(rng);
          break;
        case 7:
          Model();
          break;
        default:
          ValidDistance(rng);
      }
    }
  }

  const Counts& counts() const { return counts_; }

 private:
  std::vector<SurfacePoint> Points(std::mt19937& rng, int n) {
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<SurfacePoint> out;
    for (int i = 0; i < n; ++i) {
      double a = u(rng), b = u(rng);
      if (a + b > 1) a = 1 - a, b = 1 - b;
      out.push_back({static_cast<int32_t>(rng() % faces_), {a, b, 1 - a - b}});
    }
    return out;
  }
  static v1::SurfacePoints ToProto(const std::vector<SurfacePoint>& points) {
    v1::SurfacePoints out;
    for (const SurfacePoint& p : points) {
      out.add_faces(p.face);
      for (double w : p.w) out.add_weights(w);
    }
    return out;
  }
  v1::ModelRef Ref() const {
    v1::ModelRef ref;
    ref.set_name(model_);
    return ref;
  }
  static std::unique_ptr<grpc::ClientContext> Context() {
    auto context = std::make_unique<grpc::ClientContext>();
    context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return context;
  }
  const QueryEngine* EngineOf(int64_t version) {
    const auto it = engines_.find(version);
    if (it == engines_.end()) {
      Violation(absl::StrFormat("answered by version %d, which has no reference index", version));
      return nullptr;
    }
    return it->second.get();
  }
  void Violation(const std::string& what) {
    if (++counts_.violations <= 10) {
      std::lock_guard<std::mutex> lock(print_mutex_);
      std::fprintf(stderr, "soak_driver: VIOLATION: %s\n", what.c_str());
    }
  }
  // Compares served distances with the engine's, to the bit.
  void ExpectDistances(const char* call, int64_t version, const std::vector<SurfacePoint>& a,
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

  void ValidDistance(std::mt19937& rng) {
    const int n = 1 + static_cast<int>(rng() % 64);
    const auto a = Points(rng, n), b = Points(rng, n);
    v1::DistanceRequest request;
    *request.mutable_model() = Ref();
    *request.mutable_a() = ToProto(a);
    *request.mutable_b() = ToProto(b);
    v1::DistanceResponse response;
    const grpc::Status status = stub_->Distance(Context().get(), request, &response);
    ++counts_.valid;
    if (!status.ok()) {
      Violation("Distance: " + status.error_message());
      return;
    }
    ExpectDistances("Distance", response.version(), a, b, response.distances());
  }

  void InvalidDistance(std::mt19937& rng) {
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
    ++counts_.invalid;
    if (status.error_code() != expected) {
      Violation(absl::StrFormat("invalid Distance (kind %d): code %d '%s', expected %d", kind,
                                status.error_code(), status.error_message(), expected));
    }
  }

  // Five batches, the third invalid: it alone is refused.
  void Stream(std::mt19937& rng) {
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
        ++counts_.invalid;
        if (result.error_code() != grpc::StatusCode::OUT_OF_RANGE &&
            result.error_code() != grpc::StatusCode::INVALID_ARGUMENT) {
          Violation(
              absl::StrFormat("stream: bad batch answered with code %d", result.error_code()));
        }
        continue;
      }
      ++counts_.valid;
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

  void Path(std::mt19937& rng) {
    const auto a = Points(rng, 2), b = Points(rng, 2);
    v1::PathRequest request;
    *request.mutable_model() = Ref();
    *request.mutable_a() = ToProto(a);
    *request.mutable_b() = ToProto(b);
    v1::PathResponse response;
    const grpc::Status status = stub_->Path(Context().get(), request, &response);
    ++counts_.valid;
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

  void Field(std::mt19937& rng) {
    const auto sources = Points(rng, 1 + static_cast<int>(rng() % 3));
    v1::DistanceFieldRequest request;
    *request.mutable_model() = Ref();
    *request.mutable_sources() = ToProto(sources);
    auto context = Context();
    auto reader = stub_->DistanceField(context.get(), request);
    v1::DistanceFieldChunk chunk;
    std::vector<double> got;
    int64_t version = 0;
    while (reader->Read(&chunk)) {
      got.insert(got.end(), chunk.distances().begin(), chunk.distances().end());
      version = chunk.version();
    }
    const grpc::Status status = reader->Finish();
    ++counts_.valid;
    if (!status.ok()) {
      Violation("DistanceField: " + status.error_message());
      return;
    }
    const QueryEngine* engine = EngineOf(version);
    if (engine == nullptr) return;
    auto field = engine->Field(sources);
    if (!field.ok() || field->distance != got) {
      Violation(absl::StrFormat("DistanceField differs from offline (version %d)", version));
    }
  }

  void ExpMap(std::mt19937& rng) {
    const auto centre = Points(rng, 1);
    const double radius = 0.2 + 0.6 * std::uniform_real_distribution<double>(0, 1)(rng);
    v1::ExpMapRequest request;
    *request.mutable_model() = Ref();
    *request.mutable_center() = ToProto(centre);
    request.set_radius(radius);
    auto context = Context();
    auto reader = stub_->ExpMap(context.get(), request);
    v1::ExpMapChunk chunk;
    std::vector<int32_t> vertices;
    std::vector<double> theta;
    int64_t version = 0;
    while (reader->Read(&chunk)) {
      vertices.insert(vertices.end(), chunk.vertices().begin(), chunk.vertices().end());
      theta.insert(theta.end(), chunk.theta().begin(), chunk.theta().end());
      version = chunk.version();
    }
    const grpc::Status status = reader->Finish();
    ++counts_.valid;
    if (!status.ok()) {
      Violation("ExpMap: " + status.error_message());
      return;
    }
    const QueryEngine* engine = EngineOf(version);
    if (engine == nullptr) return;
    query::ExpMapOptions options;
    options.radius = radius;
    auto map = query::ExpMap(*engine, centre[0], options);
    bool same = map.ok() && map->size() == vertices.size();
    for (size_t i = 0; same && i < vertices.size(); ++i) {
      same = (*map)[i].vertex == vertices[i] && (*map)[i].theta == theta[i];
    }
    if (!same) Violation(absl::StrFormat("ExpMap differs from offline (version %d)", version));
  }

  void Model() {
    v1::GetModelRequest request;
    *request.mutable_model() = Ref();
    v1::ModelInfo info;
    const grpc::Status status = stub_->GetModel(Context().get(), request, &info);
    ++counts_.valid;
    if (!status.ok()) Violation("GetModel: " + status.error_message());
  }

  std::unique_ptr<v1::Geodex::Stub> stub_;
  const std::string model_;
  const std::map<int64_t, std::shared_ptr<const QueryEngine>> engines_;
  const int64_t max_pairs_;
  const int32_t faces_;
  Counts counts_;
  std::mutex print_mutex_;
};

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app{"soak_driver: concurrent valid and invalid requests, answers checked offline."};
  std::string server, model;
  std::vector<std::string> versions;
  int threads = 8;
  double seconds = 30;
  int64_t max_pairs = 1000;
  app.add_option("--server", server, "geodex-server address")->required();
  app.add_option("--model", model, "Model name")->required();
  app.add_option("--version", versions, "V=INDEX: the index of version V, for the answers")
      ->required();
  app.add_option("--threads", threads, "Concurrent clients")->check(CLI::Range(1, 256));
  app.add_option("--seconds", seconds, "Run time")->check(CLI::Range(0.1, 86400.0));
  app.add_option("--max-pairs", max_pairs, "The server's --max-pairs")
      ->check(CLI::Range(1, 100000));
  CLI11_PARSE(app, argc, argv);

  std::map<int64_t, std::shared_ptr<const geodex::query::QueryEngine>> engines;
  for (const std::string& v : versions) {
    const size_t eq = v.find('=');
    if (eq == std::string::npos) {
      std::fprintf(stderr, "soak_driver: --version wants V=INDEX, got %s\n", v.c_str());
      return 2;
    }
    auto index = geodex::index::Index::Open(v.substr(eq + 1));
    if (!index.ok()) {
      std::fprintf(stderr, "soak_driver: %s\n", index.status().ToString().c_str());
      return 2;
    }
    engines[std::stoll(v.substr(0, eq))] = *geodex::query::QueryEngine::Create(*index);
  }
  geodex::Soak soak(grpc::CreateChannel(server, grpc::InsecureChannelCredentials()), model, engines,
                    max_pairs);
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back([&, t] { soak.Run(1000 + t, until); });
  for (std::thread& t : pool) t.join();
  const geodex::Counts& c = soak.counts();
  std::printf(
      "soak_driver: %d threads, %.0f s: %lld valid calls, %lld invalid refused, "
      "%lld violations\n",
      threads, seconds, static_cast<long long>(c.valid.load()),
      static_cast<long long>(c.invalid.load()), static_cast<long long>(c.violations.load()));
  if (c.violations.load() != 0) return 1;
  // A run that made no valid or no invalid call checked nothing (clients that
  // never got to send): it must not look like a clean soak.
  if (c.valid.load() == 0 || c.invalid.load() == 0) {
    std::fprintf(
        stderr,
        "soak_driver: FAILED: %lld valid and %lld invalid calls made: nothing was checked\n",
        static_cast<long long>(c.valid.load()), static_cast<long long>(c.invalid.load()));
    return 1;
  }
  return 0;
}
