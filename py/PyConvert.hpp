// Conversions between Python objects and the core's types, shared by the binding files.
// YADE registers converters for Eigen's Vector3d/Quaterniond process-wide, so
// values we return are YADE's own Vector3/Quaternion. Inputs are accepted as YADE vectors
// or as any 3-sequence, so plain tuples work too.
#pragma once
#define NO_IMPORT_ARRAY
#define PY_ARRAY_UNIQUE_SYMBOL MPMSDEM_ARRAY_API
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <boost/python.hpp>
#include <numpy/arrayobject.h>

#include <string>
#include <vector>

#include "common/Error.hpp"
#include "common/Types.hpp"

namespace mpmsdem {
namespace py {

namespace bp = boost::python;

// A 3-vector from a YADE Vector3 or any sequence of three numbers; `name` is used in errors.
inline Vec3 toVec3(const bp::object& o, const char* name) {
  bp::extract<Vec3> direct(o);
  if (direct.check()) return direct();
  if (!PySequence_Check(o.ptr()) || PySequence_Size(o.ptr()) != 3)
    throw ParameterError(std::string(name) + ": must be a 3-vector (Vector3 or a sequence of 3 numbers)");
  const double x = bp::extract<double>(o[0]), y = bp::extract<double>(o[1]), z = bp::extract<double>(o[2]);
  return Vec3(x, y, z);
}

// A unit quaternion from a YADE Quaternion or a sequence (w, x, y, z).
inline Quat toQuat(const bp::object& o, const char* name) {
  bp::extract<Quat> direct(o);
  if (direct.check()) return direct().normalized();
  if (!PySequence_Check(o.ptr()) || PySequence_Size(o.ptr()) != 4)
    throw ParameterError(std::string(name) + ": must be a Quaternion or a sequence (w, x, y, z)");
  const double w = bp::extract<double>(o[0]), x = bp::extract<double>(o[1]), y = bp::extract<double>(o[2]),
               z = bp::extract<double>(o[3]);
  const Quat q(w, x, y, z);
  if (q.norm() < 1e-12) throw ParameterError(std::string(name) + ": quaternion must have a non-zero norm");
  return q.normalized();
}

// A new, unfilled numpy array of doubles with shape (rows, cols) (cols == 0: 1-D); *data
// receives its buffer.
inline bp::object numpyEmpty(npy_intp rows, npy_intp cols, double** data) {
  npy_intp dims[2] = {rows, cols};
  PyObject* arr = PyArray_SimpleNew(cols == 0 ? 1 : 2, dims, NPY_DOUBLE);
  if (!arr) bp::throw_error_already_set();
  *data = static_cast<double*>(PyArray_DATA(reinterpret_cast<PyArrayObject*>(arr)));
  return bp::object(bp::handle<>(arr));
}

// A new numpy array of doubles with shape (rows, cols) (cols == 0: 1-D) copied from `data`.
inline bp::object numpyArray(const double* data, npy_intp rows, npy_intp cols) {
  double* out;
  bp::object arr = numpyEmpty(rows, cols, &out);
  std::copy(data, data + rows * (cols == 0 ? 1 : cols), out);
  return arr;
}

inline bp::object numpyArrayInt(const std::vector<long>& data) {
  npy_intp dims[1] = {static_cast<npy_intp>(data.size())};
  PyObject* arr = PyArray_SimpleNew(1, dims, NPY_LONG);
  if (!arr) bp::throw_error_already_set();
  std::copy(data.begin(), data.end(), static_cast<long*>(PyArray_DATA(reinterpret_cast<PyArrayObject*>(arr))));
  return bp::object(bp::handle<>(arr));
}

// The numbers of a Python sequence of any length, as doubles.
inline std::vector<double> sequenceOfDoubles(const bp::object& values) {
  std::vector<double> out;
  for (long i = 0, n = bp::len(values); i < n; ++i) out.push_back(bp::extract<double>(values[i]));
  return out;
}

// A contiguous copy of a numpy-compatible object as doubles; checks the element count.
inline std::vector<double> fromNumpy(const bp::object& o, std::size_t expected, const char* name) {
  PyObject* arr = PyArray_FROMANY(o.ptr(), NPY_DOUBLE, 0, 0, NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED);
  if (!arr) bp::throw_error_already_set();
  bp::object holder{bp::handle<>(arr)};
  auto* a = reinterpret_cast<PyArrayObject*>(arr);
  const std::size_t n = static_cast<std::size_t>(PyArray_SIZE(a));
  if (n != expected)
    throw ParameterError(std::string(name) + ": must hold " + std::to_string(expected) + " numbers, got " +
                         std::to_string(n));
  const double* p = static_cast<const double*>(PyArray_DATA(a));
  return std::vector<double>(p, p + n);
}

void exportShapes();
void exportSdem();
void exportMpm();
void exportCoupling();
void exportParameters();

}  // namespace py
}  // namespace mpmsdem
