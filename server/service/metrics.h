#pragma once

// Prometheus metrics of geodex-server (prometheus-cpp), served over HTTP on a
// port of their own:
//
//   geodex_requests_total{method,model,code}         finished calls
//   geodex_pairs_total{method,model}                 work items: pairs,
//       matrix cells, field sources x vertices, positions, mesh vertices +
//       faces sent
//   geodex_request_duration_seconds{method,model}    call latency; for
//       StreamDistances, the latency of each batch (read to answer queued)
//   geodex_errors_total{method,code}                 calls and stream batches
//       that failed
//   geodex_stream_batches_total{model,code}          StreamDistances batches
//   geodex_active_streams                            streaming calls running
//   geodex_model_state{model,state}                  1 for the current state
//   geodex_model_mapped_bytes{model}                 bytes of mapped index
//       files of the served versions
//   geodex_model_served_version{model}               newest served version
//
// `model` is the name of a known model, or "" when the request named none
// that exists (unknown names never become label values).
//
// Thread safety: every method is safe from any thread.

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "prometheus/counter.h"
#include "prometheus/family.h"
#include "prometheus/gauge.h"
#include "prometheus/histogram.h"
#include "prometheus/registry.h"
#include "server/registry/model_registry.h"

namespace prometheus {
class Exposer;
}

namespace geodex::server {

class Metrics {
 public:
  Metrics();
  ~Metrics();
  Metrics(const Metrics&) = delete;
  Metrics& operator=(const Metrics&) = delete;

  // Serves GET /metrics on `address` ("host:port"; port 0 picks a free one).
  // Errors: Unavailable if it cannot listen there.
  absl::Status Serve(const std::string& address);
  // The port /metrics is served on, or -1.
  int port() const;

  // One finished unary or streaming call.
  void RecordCall(std::string_view method, std::string_view model, absl::StatusCode code,
                  int64_t pairs, double seconds);
  // One answered StreamDistances batch.
  void RecordBatch(std::string_view model, absl::StatusCode code, int64_t pairs, double seconds);
  void SetActiveStreams(int64_t streams);
  // Follows the registry: per-model state, mapped bytes, version; the series
  // of removed models are dropped.
  void UpdateModels(const RegistrySnapshot& snapshot);

  // The current values in the Prometheus text format (what /metrics returns).
  std::string Text() const;

 private:
  struct MethodModel {
    prometheus::Counter* pairs;
    prometheus::Histogram* latency;
  };
  struct ModelGauges {
    std::map<std::string, prometheus::Gauge*> state;  // by state name
    prometheus::Gauge* mapped_bytes;
    prometheus::Gauge* served_version;
  };
  MethodModel& GetMethodModel(std::string_view method, std::string_view model);
  prometheus::Counter& GetCounter(prometheus::Family<prometheus::Counter>& family,
                                  const std::map<std::string, std::string>& labels);

  std::shared_ptr<prometheus::Registry> registry_;
  prometheus::Family<prometheus::Counter>& requests_;
  prometheus::Family<prometheus::Counter>& pairs_;
  prometheus::Family<prometheus::Histogram>& latency_;
  prometheus::Family<prometheus::Counter>& errors_;
  prometheus::Family<prometheus::Counter>& batches_;
  prometheus::Family<prometheus::Gauge>& active_streams_family_;
  prometheus::Gauge& active_streams_;
  prometheus::Family<prometheus::Gauge>& model_state_;
  prometheus::Family<prometheus::Gauge>& model_mapped_bytes_;
  prometheus::Family<prometheus::Gauge>& model_version_;

  mutable std::mutex mutex_;  // guards the caches below (prometheus-cpp guards its own)
  std::map<std::string, MethodModel, std::less<>> method_model_;  // "method\0model"
  std::map<std::string, prometheus::Counter*, std::less<>> counters_;
  std::map<std::string, ModelGauges, std::less<>> models_;
  std::unique_ptr<prometheus::Exposer> exposer_;
};

}  // namespace geodex::server
