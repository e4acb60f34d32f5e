// pybind11 bindings of the bem_cpp core: no logic and no defaults here; those live
// in the Python wrapper bem_cpp/__init__.py.
#include <pybind11/pybind11.h>
#include "bem/version.hpp"
namespace py = pybind11;
PYBIND11_MODULE(_bem, m) {
  m.def("version", &bem::version);
}
