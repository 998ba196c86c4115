// geodex._core.build: the geodex-build job (builder::BuildIndexFile, the same
// library call as the command line) from Python, with the GIL released while
// it runs and the builder's progress handed to a Python callable.

#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "core/build/build_pipeline.h"
#include "core/python/bindings.h"
#include "core/python/python_status.h"
#include "pybind11/pybind11.h"

namespace geodex::python {
namespace {

namespace py = pybind11;

// Calls into Python from the builder's threads: one at a time (the builder
// serialises its progress calls; the log comes from the calling thread), with
// the GIL taken for each. The first exception a callable raises is kept and
// later calls are skipped; Build raises it once the build is over (the
// builder cannot be interrupted).
class Callbacks {
 public:
  Callbacks(py::object progress, py::object log)
      : progress_(std::move(progress)), log_(std::move(log)) {}

  void Progress(const builder::Progress& p) {
    if (progress_.is_none()) return;
    Call([&] { progress_(std::string(p.phase), p.done, p.total); });
  }
  void Log(const std::string& line) {
    Call([&] { log_(line); });
  }
  // Raises the kept exception, if any (with the GIL held).
  void RaiseIfFailed() {
    if (error_ != nullptr) {
      std::unique_ptr<py::error_already_set> error = std::move(error_);
      throw *error;
    }
  }
  // Python objects are released with the GIL held.
  ~Callbacks() {
    py::gil_scoped_acquire gil;
    error_.reset();
    progress_ = py::object();
    log_ = py::object();
  }

 private:
  template <class Fn>
  void Call(Fn fn) {
    std::lock_guard<std::mutex> lock(mutex_);
    py::gil_scoped_acquire gil;
    if (error_ != nullptr) return;
    try {
      fn();
    } catch (py::error_already_set& e) {
      error_ = std::make_unique<py::error_already_set>(std::move(e));
    }
  }

  std::mutex mutex_;
  py::object progress_;
  py::object log_;
  std::unique_ptr<py::error_already_set> error_;
};

// Builds the index of `mesh_path` (a mesh file, or builtin:NAME) into `out`;
// returns geodex-build's report. samples 0: none asked, so to the error
// target as geodex-build without --samples (target_error 0: the default
// target); otherwise exactly `samples`, or with target_error > 0 the first
// round's. max_samples 0: the default cap.
std::string Build(const std::string& mesh_path, const std::string& out, int32_t samples,
                  double target_error, int32_t max_samples, uint64_t seed, int threads, bool strict,
                  bool split, bool calibrate, py::object progress, py::object log) {
  auto callbacks = std::make_shared<Callbacks>(std::move(progress), std::move(log));
  builder::PipelineOptions options;
  if (samples > 0) options.build.num_samples = samples;
  options.target_error = target_error;
  options = builder::WithSampleDefaults(std::move(options), samples > 0);
  options.build.seed = seed;
  options.build.threads = threads;
  options.build.split_long_edges = split;
  options.build.progress = [callbacks](const builder::Progress& p) { callbacks->Progress(p); };
  options.repair.strict = strict;
  options.calibrate = calibrate;
  options.max_samples = max_samples;
  options.log = [callbacks](const std::string& line) { callbacks->Log(line); };
  absl::StatusOr<builder::BuildReport> report;
  {
    py::gil_scoped_release release;
    report = builder::BuildIndexFile(mesh_path, out, options);
    options.build.progress = nullptr;  // the last references to the callbacks
    options.log = nullptr;
  }
  callbacks->RaiseIfFailed();
  return ValueOrThrow(std::move(report)).text;
}

}  // namespace

void BindBuild(py::module_& m) {
  m.def("build", &Build, py::arg("mesh_path"), py::arg("out"), py::arg("samples"),
        py::arg("target_error"), py::arg("max_samples"), py::arg("seed"), py::arg("threads"),
        py::arg("strict"), py::arg("split"), py::arg("calibrate"), py::arg("progress"),
        py::arg("log"),
        "Builds an index file from a mesh file (geodex.build wraps it); returns the report.");
}

}  // namespace geodex::python
