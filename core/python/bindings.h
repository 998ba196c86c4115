#pragma once

// The parts of the module geodex._core (core_module.cc): the index
// (index_bindings.cc) and the builder (build_bindings.cc).

#include "pybind11/pybind11.h"

namespace geodex::python {

void BindIndex(pybind11::module_& m);
void BindBuild(pybind11::module_& m);

}  // namespace geodex::python
