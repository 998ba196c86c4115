#pragma once

// One soak client set (soak_driver.cc): threads that send a geodex-server a
// random mix of valid requests (Distance, StreamDistances, Path, the
// server-streaming calls of Soak::StreamedCalls, GetModel) and invalid ones (faces past the end,
// NaN and negative weights, wrong lengths, an unknown model, too many pairs, a bad batch inside a
// good stream). Every valid answer is compared, to the bit, with the offline engine of the version
// that answered it; every invalid request must be refused with its code while the rest of the call
// (the other batches of a stream) is answered.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "core/query/engine/query_engine.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "grpcpp/channel.h"

namespace geodex::soak {

// Calls made and violations seen, at one moment.
struct SoakTotals {
  int64_t valid = 0;       // valid calls made
  int64_t invalid = 0;     // invalid calls (or stream batches) made
  int64_t violations = 0;  // answers that differed, codes that were wrong
};

// Thread-safe: Run and Step may be called from several threads at once,
// each with its own generator.
class Soak {
 public:
  // `engines`: the offline engine of each version the server may answer
  // with (not empty); `max_pairs`: the server's --max-pairs.
  Soak(std::shared_ptr<grpc::Channel> channel, std::string model,
       std::map<int64_t, std::shared_ptr<const query::QueryEngine>> engines, int64_t max_pairs);

  // Random calls from a generator seeded with `seed` until `until`.
  void Run(uint32_t seed, std::chrono::steady_clock::time_point until);

  // One random call, drawn with `rng`.
  void Step(std::mt19937& rng);

  SoakTotals totals() const;

 private:
  using SurfacePoint = mesh::SurfacePoint;

  std::vector<SurfacePoint> Points(std::mt19937& rng, int n);
  static v1::SurfacePoints ToProto(const std::vector<SurfacePoint>& points);
  v1::ModelRef Ref() const;
  static std::unique_ptr<grpc::ClientContext> Context();
  // The engine of `version`; nullptr (and a violation) when there is none.
  const query::QueryEngine* EngineOf(int64_t version);
  // Counts a violation; the first ten are printed.
  void Violation(const std::string& what);
  // Compares served distances with the engine's, to the bit.
  void ExpectDistances(const char* call, int64_t version, const std::vector<SurfacePoint>& a,
                       const std::vector<SurfacePoint>& b,
                       const google::protobuf::RepeatedField<double>& got);

  // The version that answered a call, and its engine (nullptr: none).
  struct Answered {
    int64_t version = 0;
    const query::QueryEngine* engine = nullptr;
  };
  template <typename Chunk, typename Open, typename Take>
  Answered ReadStream(const char* call, Open open, Take take);

  void ValidDistance(std::mt19937& rng);
  void InvalidDistance(std::mt19937& rng);
  void Stream(std::mt19937& rng);
  void Path(std::mt19937& rng);
  void Model();

  // The server-streaming calls of the mix, one entry each (soak_client.cc):
  // an entry sends a random request, reads the stream to its end
  // (ReadStream) and compares the answer with the offline engine's.
  using StreamedCall = void (*)(Soak& soak, std::mt19937& rng);
  static const std::vector<StreamedCall>& StreamedCalls();

  std::unique_ptr<v1::Geodex::Stub> stub_;
  const std::string model_;
  const std::map<int64_t, std::shared_ptr<const query::QueryEngine>> engines_;
  const int64_t max_pairs_;
  const int32_t faces_;
  std::atomic<int64_t> valid_{0}, invalid_{0}, violations_{0};
  std::mutex print_mutex_;
};

}  // namespace geodex::soak
