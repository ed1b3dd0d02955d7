// The _mpmsdem Boost.Python module: entry point, exception translation.
// Python users import the `mpmsdem` package, which wraps this module.
#define PY_ARRAY_UNIQUE_SYMBOL MPMSDEM_ARRAY_API
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <boost/python.hpp>
#include <numpy/arrayobject.h>

#include "PyConvert.hpp"
#include "mpm/GridBoundary.hpp"

namespace {

void translateParameter(const mpmsdem::ParameterError& e) { PyErr_SetString(PyExc_ValueError, e.what()); }
void translateRuntime(const mpmsdem::RuntimeFailure& e) { PyErr_SetString(PyExc_RuntimeError, e.what()); }

void* initNumpy() {
  import_array();
  return nullptr;
}

}  // namespace

BOOST_PYTHON_MODULE(_mpmsdem) {
  initNumpy();
  boost::python::register_exception_translator<mpmsdem::ParameterError>(translateParameter);
  boost::python::register_exception_translator<mpmsdem::RuntimeFailure>(translateRuntime);
  mpmsdem::py::exportShapes();
  mpmsdem::py::exportSdem();
  mpmsdem::py::exportMpm();
  mpmsdem::py::exportCoupling();
  mpmsdem::py::exportParameters();
  // cells inside each face of the grid box where its walls act (mpm/GridBoundary.hpp)
  boost::python::scope().attr("wallLayer") = mpmsdem::mpm::kWallLayer;
}
