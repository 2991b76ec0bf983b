#include "convert.hpp"

#include <cmath>
#include <new>

namespace refit::python {

namespace {

PyObject* make_error_class(py::module_& m, const char* name, const char* doc, PyObject* bases, int exit_code) {
  const std::string qualified = std::string("refit.") + name;
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases, nullptr);
  if (!cls) throw py::error_already_set();
  py::handle h(cls);
  h.attr("exit_code") = exit_code;
  m.attr(name) = h;  // the module keeps a reference; `cls` stays alive as long as Python
  return cls;
}

}  // namespace

void register_errors(py::module_& m) {
  // Kept for the life of the interpreter: the translator below needs them.
  static PyObject* base = nullptr;
  static PyObject* input = nullptr;
  static PyObject* usage = nullptr;
  static PyObject* resource = nullptr;
  base = make_error_class(m, "Error",
                          "Every error of refit. `exit_code` is the command line's exit code for the same failure "
                          "(docs/cli-errors.md); the message is the line the command line prints after "
                          "'refit: error: '.",
                          PyExc_RuntimeError, 1);
  input = make_error_class(m, "InputError",
                           "Bad input (exit code 1): the message names the file (and line) and the problem.", base, 1);
  const py::tuple usage_bases = py::make_tuple(py::handle(base), py::handle(PyExc_ValueError));
  usage = make_error_class(m, "UsageError",
                           "An argument value the command line refuses as a usage error (exit code 2).",
                           usage_bases.ptr(), 2);
  const py::tuple resource_bases = py::make_tuple(py::handle(base), py::handle(PyExc_MemoryError));
  resource = make_error_class(m, "ResourceError", "Out of resources: memory (exit code 3).", resource_bases.ptr(), 3);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const UsageError& e) {
      PyErr_SetString(usage, e.what());
    } catch (const ResourceError& e) {  // an estimate above the memory there is
      PyErr_SetString(resource, e.what());
    } catch (const Error& e) {
      PyErr_SetString(input, e.what());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(resource, "out of memory");
    }
  });
}

py::array_t<double> to_numpy(Points&& p) {
  auto* owned = new Points(std::move(p));
  py::capsule free_when_done(owned, [](void* q) { delete static_cast<Points*>(q); });
  const auto n = static_cast<py::ssize_t>(owned->rows());
  // Points is column-major (x, y and z each contiguous): numpy reads it through strides.
  return py::array_t<double>({n, py::ssize_t(3)}, {py::ssize_t(sizeof(double)), py::ssize_t(sizeof(double)) * n},
                             owned->data(), free_when_done);
}

py::array_t<double> view(const Points& p, py::handle owner) {
  const auto n = static_cast<py::ssize_t>(p.rows());
  py::array_t<double> a({n, py::ssize_t(3)}, {py::ssize_t(sizeof(double)), py::ssize_t(sizeof(double)) * n}, p.data(),
                        owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

Points points_from(const py::array_t<double, py::array::forcecast>& a, const std::string& what) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw UsageError(what + ": expected an N x 3 array of positions");
  Points p(a.shape(0), 3);
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    for (int k = 0; k < 3; ++k) p(i, k) = r(i, k);
  return p;
}

py::object to_python(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return py::none();
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(j.get<std::int64_t>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<std::uint64_t>());
    case nlohmann::json::value_t::number_float: return py::float_(j.get<double>());
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const auto& v : j) l.append(to_python(v));
      return l;
    }
    case nlohmann::json::value_t::object: {
      py::dict d;
      for (const auto& [k, v] : j.items()) d[py::str(k)] = to_python(v);
      return d;
    }
    default: return py::none();
  }
}

}  // namespace refit::python
