#include "server/service/metrics.h"

#include <exception>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "prometheus/exposer.h"
#include "prometheus/text_serializer.h"

namespace geodex::server {
namespace {

// 20 us .. ~20 s, factor 2.
prometheus::Histogram::BucketBoundaries LatencyBuckets() {
  prometheus::Histogram::BucketBoundaries b;
  for (double s = 20e-6; s < 30; s *= 2) b.push_back(s);
  return b;
}

std::string CodeName(absl::StatusCode code) { return absl::StatusCodeToString(code); }

}  // namespace

Metrics::Metrics()
    : registry_(std::make_shared<prometheus::Registry>()),
      requests_(prometheus::BuildCounter()
                    .Name("geodex_requests_total")
                    .Help("Finished calls by method, model and status code")
                    .Register(*registry_)),
      pairs_(
          prometheus::BuildCounter()
              .Name("geodex_pairs_total")
              .Help("Work items answered (pairs, matrix cells, field source-vertices, positions)")
              .Register(*registry_)),
      latency_(prometheus::BuildHistogram()
                   .Name("geodex_request_duration_seconds")
                   .Help("Call latency (StreamDistances: per batch)")
                   .Register(*registry_)),
      errors_(prometheus::BuildCounter()
                  .Name("geodex_errors_total")
                  .Help("Failed calls and stream batches by method and status code")
                  .Register(*registry_)),
      batches_(prometheus::BuildCounter()
                   .Name("geodex_stream_batches_total")
                   .Help("StreamDistances batches by model and status code")
                   .Register(*registry_)),
      active_streams_family_(prometheus::BuildGauge()
                                 .Name("geodex_active_streams")
                                 .Help("Streaming calls in progress")
                                 .Register(*registry_)),
      active_streams_(active_streams_family_.Add({})),
      model_state_(prometheus::BuildGauge()
                       .Name("geodex_model_state")
                       .Help("1 for the model's current load state")
                       .Register(*registry_)),
      model_mapped_bytes_(prometheus::BuildGauge()
                              .Name("geodex_model_mapped_bytes")
                              .Help("Bytes of index files mapped for the model's served versions")
                              .Register(*registry_)),
      model_version_(prometheus::BuildGauge()
                         .Name("geodex_model_served_version")
                         .Help("Newest served version of the model (0: none)")
                         .Register(*registry_)) {}

Metrics::~Metrics() = default;

absl::Status Metrics::Serve(const std::string& address) {
  try {
    auto exposer = std::make_unique<prometheus::Exposer>(address);
    exposer->RegisterCollectable(registry_);
    std::lock_guard<std::mutex> lock(mutex_);
    exposer_ = std::move(exposer);
  } catch (const std::exception& e) {
    return absl::UnavailableError(
        absl::StrCat("cannot serve metrics on ", address, ": ", e.what()));
  }
  return absl::OkStatus();
}

int Metrics::port() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (exposer_ == nullptr) return -1;
  const std::vector<int> ports = exposer_->GetListeningPorts();
  return ports.empty() ? -1 : ports.front();
}

Metrics::MethodModel& Metrics::GetMethodModel(std::string_view method, std::string_view model) {
  std::string key = absl::StrCat(std::string(method), std::string(1, '\0'), std::string(model));
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = method_model_.find(key);
  if (it != method_model_.end()) return it->second;
  const std::map<std::string, std::string> labels = {{"method", std::string(method)},
                                                     {"model", std::string(model)}};
  MethodModel m{&pairs_.Add(labels), &latency_.Add(labels, LatencyBuckets())};
  return method_model_.emplace(std::move(key), m).first->second;
}

prometheus::Counter& Metrics::GetCounter(prometheus::Family<prometheus::Counter>& family,
                                         const std::map<std::string, std::string>& labels) {
  std::string key = absl::StrCat(reinterpret_cast<uintptr_t>(&family));
  for (const auto& [k, v] : labels) absl::StrAppend(&key, std::string(1, '\0'), k, "=", v);
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = counters_.find(key);
  if (it != counters_.end()) return *it->second;
  prometheus::Counter* counter = &family.Add(labels);
  counters_.emplace(std::move(key), counter);
  return *counter;
}

void Metrics::RecordCall(std::string_view method, std::string_view model, absl::StatusCode code,
                         int64_t pairs, double seconds) {
  const std::string code_name = CodeName(code);
  GetCounter(requests_,
             {{"method", std::string(method)}, {"model", std::string(model)}, {"code", code_name}})
      .Increment();
  if (code != absl::StatusCode::kOk) {
    GetCounter(errors_, {{"method", std::string(method)}, {"code", code_name}}).Increment();
  }
  // Stream latency is per batch (RecordBatch); a stream's duration says
  // little about the service.
  const bool stream = method == "StreamDistances";
  MethodModel& mm = GetMethodModel(method, model);
  if (pairs > 0 && !stream) mm.pairs->Increment(static_cast<double>(pairs));
  if (!stream) mm.latency->Observe(seconds);
}

void Metrics::RecordBatch(std::string_view model, absl::StatusCode code, int64_t pairs,
                          double seconds) {
  const std::string code_name = CodeName(code);
  GetCounter(batches_, {{"model", std::string(model)}, {"code", code_name}}).Increment();
  if (code != absl::StatusCode::kOk) {
    GetCounter(errors_, {{"method", "StreamDistances"}, {"code", code_name}}).Increment();
  }
  MethodModel& mm = GetMethodModel("StreamDistances", model);
  if (pairs > 0) mm.pairs->Increment(static_cast<double>(pairs));
  mm.latency->Observe(seconds);
}

void Metrics::SetActiveStreams(int64_t streams) {
  active_streams_.Set(static_cast<double>(streams));
}

void Metrics::UpdateModels(const RegistrySnapshot& snapshot) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = models_.begin(); it != models_.end();) {
    if (snapshot.models.count(it->first) == 0) {
      for (auto& [state, gauge] : it->second.state) model_state_.Remove(gauge);
      model_mapped_bytes_.Remove(it->second.mapped_bytes);
      model_version_.Remove(it->second.served_version);
      it = models_.erase(it);
    } else {
      ++it;
    }
  }
  for (const auto& [name, model] : snapshot.models) {
    auto [it, inserted] = models_.try_emplace(name);
    ModelGauges& g = it->second;
    if (inserted) {
      for (LoadState s : {LoadState::kLoading, LoadState::kServing, LoadState::kFailed}) {
        g.state[LoadStateName(s)] =
            &model_state_.Add({{"model", name}, {"state", LoadStateName(s)}});
      }
      g.mapped_bytes = &model_mapped_bytes_.Add({{"model", name}});
      g.served_version = &model_version_.Add({{"model", name}});
    }
    for (auto& [state, gauge] : g.state) gauge->Set(state == LoadStateName(model->state) ? 1 : 0);
    int64_t bytes = 0;
    for (const auto& [version, served] : model->served) bytes += served->mapped_bytes();
    g.mapped_bytes->Set(static_cast<double>(bytes));
    g.served_version->Set(model->newest() ? static_cast<double>(model->newest()->version()) : 0);
  }
}

std::string Metrics::Text() const {
  std::ostringstream out;
  prometheus::TextSerializer().Serialize(out, registry_->Collect());
  return out.str();
}

}  // namespace geodex::server
