#pragma once

// absl::Status -> the geodex package's Python exceptions, in one place.
//
// Binding code calls ThrowIfError (or throws StatusError) wherever a core
// call fails, with or without the GIL; the translator registered by
// RegisterStatusTranslator turns the exception, once pybind11 has it back
// with the GIL held, into geodex.errors.error_for_code(code, message): the
// class of the status code (geodex.InvalidArgument, geodex.NotFound, ...) with
// the core's message, the same classes the gRPC client raises for the same
// codes.

#include <exception>
#include <string>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "pybind11/pybind11.h"

namespace geodex::python {

// A failed core call on its way to Python.
class StatusError : public std::exception {
 public:
  explicit StatusError(absl::Status status)
      : status_(std::move(status)), what_(status_.ToString()) {}
  const absl::Status& status() const { return status_; }
  const char* what() const noexcept override { return what_.c_str(); }

 private:
  absl::Status status_;
  std::string what_;
};

// Throws StatusError unless `status` is OK.
inline void ThrowIfError(const absl::Status& status) {
  if (!status.ok()) throw StatusError(status);
}

// The value of `value`, or throws its StatusError.
template <class T>
T ValueOrThrow(absl::StatusOr<T> value) {
  if (!value.ok()) throw StatusError(value.status());
  return *std::move(value);
}

// Registers the translator of StatusError (imports geodex.errors, once).
void RegisterStatusTranslator(pybind11::module_& m);

}  // namespace geodex::python
