#include "core/python/python_status.h"

namespace geodex::python {

namespace py = pybind11;

void RegisterStatusTranslator(py::module_& m) {
  // geodex.errors is pure Python and imports nothing of this module; kept
  // alive by the module for as long as the translator may run.
  py::object errors = py::module_::import("geodex.errors");
  m.attr("_errors") = errors;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const StatusError& e) {
      py::object factory = py::module_::import("geodex.errors").attr("error_for_code");
      py::object error =
          factory(static_cast<int>(e.status().code()), std::string(e.status().message()));
      PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
    }
  });
}

}  // namespace geodex::python
