// geodex._core: the compiled half of the Python package geodex, bindings of
// core (the query engine in the mesh file's ids, and the builder). The Python
// classes users see (geodex.Index, geodex.build) wrap it in
// geodex/_inprocess.py, which validates arrays first.

#include "core/python/bindings.h"
#include "core/python/python_status.h"
#include "pybind11/pybind11.h"

PYBIND11_MODULE(_core, m) {
  m.doc() = "Bindings of geodex's core: geodex.Index and geodex.build wrap them.";
  geodex::python::RegisterStatusTranslator(m);
  geodex::python::BindIndex(m);
  geodex::python::BindBuild(m);
}
