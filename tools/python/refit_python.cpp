// The Python module `refit` (pybind11): garments, bodies and feature files in,
// a binding made once and applied to many bodies B, numpy arrays out. The engine
// works with the GIL released; refit::Error becomes refit.Error with the message
// the command line prints after "refit: error: ".
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/metrics/render.hpp>
#include <refit/pipeline/resize.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace refit;

namespace {

// An N x 3 numpy array that owns `p` (moved to the heap): no copy of the positions.
py::array_t<double> to_numpy(Points&& p) {
  auto* owned = new Points(std::move(p));
  py::capsule free_when_done(owned, [](void* q) { delete static_cast<Points*>(q); });
  const auto n = static_cast<py::ssize_t>(owned->rows());
  return py::array_t<double>({n, py::ssize_t(3)}, {py::ssize_t(sizeof(double)), py::ssize_t(sizeof(double)) * n},
                             owned->data(), free_when_done);
}

// A read-only numpy view of `p`, kept alive by `owner`.
py::array_t<double> view(const Points& p, py::handle owner) {
  const auto n = static_cast<py::ssize_t>(p.rows());
  py::array_t<double> a({n, py::ssize_t(3)}, {py::ssize_t(sizeof(double)), py::ssize_t(sizeof(double)) * n}, p.data(),
                        owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

Points from_numpy(const py::array_t<double, py::array::forcecast>& a, const char* what) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw Error(std::string(what) + ": expected an N x 3 array of positions");
  Points p(a.shape(0), 3);
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    for (int k = 0; k < 3; ++k) p(i, k) = r(i, k);
  return p;
}

// nlohmann::json -> Python objects.
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

struct Features {
  std::vector<FeatureSpec> specs;
  std::string path;
};

struct Result {
  py::array_t<double> positions, warped;
  py::dict report;
  std::vector<std::string> warnings;
};

Stage stage_of(const std::string& s) {
  if (s == "warp") return Stage::Warp;
  if (s == "features") return Stage::Features;
  if (s == "full") return Stage::Full;
  throw Error("stage must be warp, features or full, not '" + s + "'");
}

class Binding {
 public:
  Binding(std::shared_ptr<const Garment> garment, const BodyMesh& body_a, const Features* features,
          const std::string& units, const std::string& stage, const std::string& symmetry, bool collision,
          double clearance, std::size_t threads)
      : garment_(std::move(garment)), threads_(threads) {
    if (!(clearance >= 0.0 && clearance <= 10.0)) throw Error("clearance must be between 0 and 10 cm");
    ResizeOptions o;
    o.units = units;
    metres_per_unit(units);  // throws for unknown units
    o.stage = stage_of(stage);
    o.symmetry = parse_symmetry(symmetry);
    o.collision = collision;
    o.clearance_cm = clearance;
    std::vector<FeatureSpec> specs = features ? features->specs : std::vector<FeatureSpec>{};
    py::gil_scoped_release unlocked;
    const ThreadLimit limit(threads_);
    binding_ = std::make_unique<GarmentBinding>(garment_, body_a, o, std::move(specs), Progress(false));
  }

  Result resize(const BodyMesh& body_b) const {
    ResizeResult r;
    {
      py::gil_scoped_release unlocked;
      const ThreadLimit limit(threads_);
      r = binding_->resize(body_b, Progress(false));
    }
    Result out;
    out.positions = to_numpy(std::move(r.positions));
    out.warped = to_numpy(std::move(r.warped));
    out.report = to_python(r.report);
    out.warnings = r.warnings;
    return out;
  }

  Result resize_to(const py::array_t<double, py::array::forcecast>& vertices) const {
    BodyMesh b = binding_->body_a().mesh();
    b.vertices = from_numpy(vertices, "body B vertices");
    b.name = "body_b";
    b.path = "<array>";
    return resize(b);
  }

 private:
  std::shared_ptr<const Garment> garment_;
  std::size_t threads_;
  std::unique_ptr<GarmentBinding> binding_;
};

}  // namespace

PYBIND11_MODULE(refit, m) {
  m.doc() =
      "Refit: resize a 3D garment from body A to body B, keeping the shape the designer meant.\n\n"
      "    g = refit.read_garment('dress_on_A.obj')\n"
      "    a = refit.read_body('A.obj')\n"
      "    b = refit.Binding(g, a, features=refit.read_features('features.json'))\n"
      "    r = b.resize(refit.read_body('B.obj'))   # or b.resize(vertices_of_B), an N x 3 array\n"
      "    refit.write_garment(g, r.positions, 'dress_on_B.obj')\n\n"
      "Errors are refit.Error, with the message the command line prints.";
  m.attr("__version__") = kVersion;
  py::register_exception<Error>(m, "Error", PyExc_RuntimeError).doc() =
      "Bad input: the message names the file (and line) and the problem.";

  py::class_<Garment, std::shared_ptr<Garment>>(m, "Garment", "A garment OBJ: positions, faces, lines, points and the file's other lines.")
      .def_property_readonly("positions", [](py::object self) { return view(self.cast<const Garment&>().positions, self); },
                             "N x 3 vertex positions (a read-only view)")
      .def_property_readonly("vertex_count", [](const Garment& g) { return g.positions.rows(); })
      .def_property_readonly("face_count", [](const Garment& g) { return g.faces.rows(); })
      .def("__repr__", [](const Garment& g) {
        return "<refit.Garment " + std::to_string(g.positions.rows()) + " vertices, " + std::to_string(g.faces.rows()) +
               " faces>";
      });
  py::class_<BodyMesh>(m, "Body", "A body mesh; bodies A and B share their triangles.")
      .def_property_readonly("vertices", [](py::object self) { return view(self.cast<const BodyMesh&>().vertices, self); },
                             "V x 3 vertex positions (a read-only view)")
      .def_property_readonly("triangle_count", [](const BodyMesh& b) { return b.triangles.size(); })
      .def_readonly("name", &BodyMesh::name)
      .def("with_vertices",
           [](const BodyMesh& b, const py::array_t<double, py::array::forcecast>& v) {
             BodyMesh out = b;
             out.vertices = from_numpy(v, "with_vertices");
             if (out.vertices.rows() != b.vertices.rows())
               throw Error("with_vertices: " + std::to_string(out.vertices.rows()) + " vertices, the body has " +
                           std::to_string(b.vertices.rows()));
             check_body(out);
             return out;
           },
           py::arg("vertices"), "The same body with other vertex positions (a body B made from body A).")
      .def("__repr__", [](const BodyMesh& b) {
        return "<refit.Body '" + b.name + "' " + std::to_string(b.vertices.rows()) + " vertices>";
      });
  py::class_<Features>(m, "Features", "Feature curves read from a feature file (docs/feature-file.md).")
      .def("__len__", [](const Features& f) { return f.specs.size(); })
      .def_property_readonly("names", [](const Features& f) {
        std::vector<std::string> n;
        for (const FeatureSpec& s : f.specs) n.push_back(s.name);
        return n;
      });
  py::class_<Result>(m, "Result", "One resize: positions (N x 3), the warp alone, the report (dict) and warnings.")
      .def_readonly("positions", &Result::positions)
      .def_readonly("warped", &Result::warped)
      .def_readonly("report", &Result::report)
      .def_readonly("warnings", &Result::warnings);

  m.def("read_garment",
        [](const std::string& path) {
          py::gil_scoped_release unlocked;
          return std::make_shared<Garment>(read_garment_obj(path));
        },
        py::arg("path"), "Reads a garment OBJ (every line kept for write_garment).");
  m.def("write_garment",
        [](const Garment& g, const py::array_t<double, py::array::forcecast>& positions, const std::string& path) {
          const Points p = from_numpy(positions, "write_garment");
          if (p.rows() != g.positions.rows())
            throw Error("write_garment: " + std::to_string(p.rows()) + " positions for a garment of " +
                        std::to_string(g.positions.rows()) + " vertices");
          py::gil_scoped_release unlocked;
          write_garment_obj(path, g, p);
        },
        py::arg("garment"), py::arg("positions"), py::arg("path"),
        "Writes the garment's file line for line with new v positions, atomically.");
  m.def("read_body", &read_body, py::arg("path"), py::call_guard<py::gil_scoped_release>(),
        "Reads a body: .obj, .ply, .off or .stl.");
  m.def("read_features",
        [](const std::string& path, const std::string& units) { return Features{read_feature_file(path, units), path}; },
        py::arg("path"), py::arg("units") = "cm", "Reads a feature file; `units` are the garment's.");
  py::class_<Binding>(m, "Binding",
                      "What depends on the garment, body A and the features, made once; resize() applies it to any "
                      "number of bodies B.")
      .def(py::init([](std::shared_ptr<Garment> g, const BodyMesh& a, const Features* features, const std::string& units,
                       const std::string& stage, const std::string& symmetry, bool collision, double clearance,
                       std::size_t threads) {
             return std::make_unique<Binding>(std::move(g), a, features, units, stage, symmetry, collision, clearance,
                                              threads);
           }),
           py::arg("garment"), py::arg("body_a"), py::arg("features") = nullptr, py::arg("units") = "cm",
           py::arg("stage") = "full", py::arg("symmetry") = "auto", py::arg("collision") = true,
           py::arg("clearance") = 0.2, py::arg("threads") = 0,
           "garment, body A, features (or None); units cm|mm|m|in; stage warp|features|full; symmetry auto|x|none; "
           "collision and its clearance in cm; threads (0 = all cores). Results do not depend on the thread count.")
      .def("resize", &Binding::resize, py::arg("body_b"), "Resizes to a body B (same triangles as body A).")
      .def("resize", &Binding::resize_to, py::arg("vertices"),
           "Resizes to body A's triangles with these vertex positions (V x 3).");
  m.def("render",
        [](const BodyMesh& body, const Garment& garment, const py::object& positions, const std::string& path,
           const std::vector<std::string>& views, int width, int height) {
          Garment shown = garment;
          if (!positions.is_none()) {
            shown.positions = from_numpy(positions.cast<py::array_t<double, py::array::forcecast>>(), "render");
            if (shown.positions.rows() != garment.positions.rows()) throw Error("render: positions do not match the garment");
          }
          RenderOptions o;
          o.width = width;
          o.height = height;
          o.views.clear();
          for (const std::string& v : views) o.views.push_back(parse_view(v, "views"));
          Image img;
          {
            py::gil_scoped_release unlocked;
            img = refit::render(body, shown, nullptr, {}, o);
          }
          if (!path.empty()) write_png(path, img);
          py::array_t<std::uint8_t> a({img.height, img.width, 3});
          std::copy(img.rgb.begin(), img.rgb.end(), a.mutable_data());
          return a;
        },
        py::arg("body"), py::arg("garment"), py::arg("positions") = py::none(), py::arg("path") = "",
        py::arg("views") = std::vector<std::string>{"front"}, py::arg("width") = 800, py::arg("height") = 1000,
        "Ray-traced picture of the body with the garment (at `positions` if given): an H x W x 3 uint8 array, also "
        "written as PNG when `path` is given.");
}
