#pragma once
// Conversions between the engine's types and Python's for the module `refit`:
// positions as numpy arrays (views or owned, never copied where the engine can
// keep the buffer), JSON reports as dicts, and the exception classes that give
// Python the command line's exit classes.
#include <refit/core/error.hpp>
#include <refit/core/types.hpp>

#include <nlohmann/json.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

namespace refit::python {

namespace py = pybind11;

/// An argument value the command line would refuse as a usage error (exit 2).
struct UsageError : Error {
  using Error::Error;
};

/// Creates refit.Error and its subclasses InputError (exit 1), UsageError (exit 2)
/// and ResourceError (exit 3) in `m`, and translates the engine's exceptions to them.
void register_errors(py::module_& m);

/// An N x 3 numpy array that owns `p` (moved to the heap): no copy of the positions.
py::array_t<double> to_numpy(Points&& p);

/// A read-only numpy view of `p`, kept alive by `owner`.
py::array_t<double> view(const Points& p, py::handle owner);

/// An N x 3 array of positions; UsageError naming `what` for another shape.
Points points_from(const py::array_t<double, py::array::forcecast>& a, const std::string& what);

/// A JSON value as Python objects (dicts, lists, numbers, strings, None).
py::object to_python(const nlohmann::json& j);

}  // namespace refit::python
