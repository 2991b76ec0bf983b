// The extension `refit._refit` (pybind11) behind the Python package `refit`:
// garments, bodies and feature files in (files or numpy arrays), a binding made
// once and applied to many bodies B, numpy arrays out, metrics and pictures.
// The engine works with the GIL released; errors become refit.Error subclasses
// with the command line's message and exit class (convert.hpp).
#include "convert.hpp"

#include <refit/core/heap.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/metrics/metrics.hpp>
#include <refit/metrics/render.hpp>
#include <refit/pipeline/resize.hpp>

#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace refit;
using python::UsageError;

namespace {

using IndexArray = py::array_t<std::int64_t, py::array::forcecast | py::array::c_style>;

struct Features {
  std::vector<FeatureSpec> specs;
  std::string path, units;  // the garment units the file was read for (its numbers are scaled to them)
};

struct Result {
  py::array_t<double> positions, warped;
  py::dict report;
  std::vector<std::string> warnings;
};

// The option checks of `refit resize`, with its exit class (usage) and its words.
void check_units(const std::string& units) {
  if (units != "cm" && units != "mm" && units != "m" && units != "in")
    throw UsageError("units: '" + units + "' is not one of cm, mm, m, in");
}
void check_threads(long threads) {
  if (threads < 0 || threads > 1024) throw UsageError("threads: " + std::to_string(threads) + " is outside 0 to 1024");
}

Stage stage_of(const std::string& s) {
  if (s == "warp") return Stage::Warp;
  if (s == "features") return Stage::Features;
  if (s == "full") return Stage::Full;
  throw UsageError("stage: unknown stage '" + s + "' (use warp, features or full)");
}

SymmetryMode symmetry_of(const std::string& s) {
  if (s == "auto" || s == "x" || s == "none") return parse_symmetry(s);
  throw UsageError("symmetry: unknown mode '" + s + "' (use auto, x or none)");
}

// CSR rows from a flat index array and the size of each row; bad input names `what`.
Csr csr_from(const IndexArray& indices, const IndexArray& sizes, std::size_t vertices, std::size_t least,
             const std::string& what) {
  if (indices.ndim() != 1 || sizes.ndim() != 1) throw UsageError(what + ": indices and sizes must be 1-D arrays");
  Csr c;
  const auto idx = indices.unchecked<1>();
  const auto n = sizes.unchecked<1>();
  std::int64_t at = 0;
  for (py::ssize_t r = 0; r < sizes.shape(0); ++r) {
    if (n(r) < static_cast<std::int64_t>(least) || at + n(r) > indices.shape(0))
      throw input_error("<array>", what + " " + std::to_string(r) + ": size " + std::to_string(n(r)) +
                                       (at + n(r) > indices.shape(0) ? " runs past the indices"
                                                                     : " is below " + std::to_string(least)));
    for (std::int64_t k = at; k < at + n(r); ++k) {
      if (idx(k) < 0 || idx(k) >= static_cast<std::int64_t>(vertices))
        throw input_error("<array>", what + " " + std::to_string(r) + ": vertex " + std::to_string(idx(k)) +
                                         " is not one of the " + std::to_string(vertices) + " vertices");
      c.indices.push_back(static_cast<Index>(idx(k)));
    }
    at += n(r);
    c.offsets.push_back(static_cast<Index>(c.indices.size()));
  }
  if (at != indices.shape(0)) throw input_error("<array>", what + ": the sizes add up to " + std::to_string(at) +
                                                               ", not the " + std::to_string(indices.shape(0)) + " indices");
  return c;
}

Garment garment_from_arrays(const py::array_t<double, py::array::forcecast>& positions, const IndexArray& face_indices,
                            const IndexArray& face_sizes, const std::optional<IndexArray>& line_indices,
                            const std::optional<IndexArray>& line_sizes) {
  Garment g;
  g.positions = python::points_from(positions, "positions");
  if (!g.positions.allFinite()) throw input_error("<array>", "a garment position is NaN or infinite");
  const auto n = static_cast<std::size_t>(g.positions.rows());
  g.faces = csr_from(face_indices, face_sizes, n, 3, "face");
  if (line_indices.has_value() != line_sizes.has_value())
    throw UsageError("line_indices and line_sizes: give both or neither");
  if (line_indices) g.lines = csr_from(*line_indices, *line_sizes, n, 2, "line");
  if (g.faces.rows() + g.lines.rows() == 0) throw input_error("<array>", "the garment has no faces and no lines");
  return g;
}

BodyMesh body_from_arrays(const py::array_t<double, py::array::forcecast>& vertices, const IndexArray& triangles,
                          const std::string& name) {
  BodyMesh b;
  b.vertices = python::points_from(vertices, "vertices");
  b.name = name;
  b.path = "<array>";
  if (triangles.ndim() != 2 || triangles.shape(1) != 3) throw UsageError("triangles: expected an M x 3 array of indices");
  const auto t = triangles.unchecked<2>();
  for (py::ssize_t r = 0; r < triangles.shape(0); ++r) {
    std::array<Index, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      if (t(r, k) < 0 || t(r, k) >= b.vertices.rows())
        throw input_error(b.path, "triangle " + std::to_string(r) + ": vertex " + std::to_string(t(r, k)) +
                                      " is not one of the " + std::to_string(b.vertices.rows()) + " vertices");
      tri[k] = static_cast<Index>(t(r, k));
    }
    b.triangles.push_back(tri);
  }
  check_body(b);
  return b;
}

// The engine's stage names to a Python callable (called with the GIL held), or silence.
Progress progress_to(const py::object& callback) {
  if (callback.is_none()) return Progress(true);
  // A handle, not an object: copies of the sink made without the GIL touch no reference count
  // (the caller's argument keeps the callable alive for the call).
  const py::handle f = callback;
  return Progress([f](const std::string& stage) {
    py::gil_scoped_acquire locked;
    f(stage);
  });
}

class Binding {
 public:
  Binding(std::shared_ptr<const Garment> garment, const BodyMesh& body_a, const Features* features,
          const std::string& units, const std::string& stage, const std::string& symmetry, bool collision,
          double clearance, long threads, bool metrics, const py::object& progress, double follow_body)
      : garment_(std::move(garment)) {
    check_units(units);
    check_threads(threads);
    if (!(clearance >= 0.0 && clearance <= 10.0))
      throw UsageError("clearance: " + std::to_string(clearance) + " is outside 0 to 10 cm");
    if (!(follow_body >= 0.0 && follow_body <= 10.0))
      throw UsageError("follow_body: " + std::to_string(follow_body) + " is outside 0 to 10 cm");
    threads_ = static_cast<std::size_t>(threads);
    ResizeOptions o;
    o.units = units;
    o.stage = stage_of(stage);
    o.symmetry = symmetry_of(symmetry);
    o.collision = collision;
    o.clearance_cm = clearance;
    o.follow_body_cm = follow_body;
    o.metrics = metrics;
    if (features && features->units != units)
      throw UsageError("features: read for units " + features->units + ", the binding's are " + units +
                       " (read_features(path, units='" + units + "'))");
    std::vector<FeatureSpec> specs = features ? features->specs : std::vector<FeatureSpec>{};
    const Progress stages = progress_to(progress);
    py::gil_scoped_release unlocked;
    const ThreadLimit limit(threads_);
    binding_ = std::make_unique<GarmentBinding>(garment_, body_a, o, std::move(specs), stages);
  }

  Result resize(const BodyMesh& body_b, const py::object& progress) const {
    ResizeResult r;
    {
      const Progress stages = progress_to(progress);
      py::gil_scoped_release unlocked;
      const ThreadLimit limit(threads_);
      r = binding_->resize(body_b, stages);
    }
    Result out;
    r.report["timings_ms"]["bind"] = binding_->bind_report();
    out.positions = python::to_numpy(std::move(r.positions));
    out.warped = python::to_numpy(std::move(r.warped));
    out.report = python::to_python(r.report);
    out.warnings = r.warnings;
    return out;
  }

  Result resize_to(const py::array_t<double, py::array::forcecast>& vertices, const py::object& progress) const {
    BodyMesh b = binding_->body_a().mesh();
    b.vertices = python::points_from(vertices, "body B vertices");
    b.name = "body_b";
    b.path = "<array>";
    return resize(b, progress);
  }

  const BodyMesh& body_a() const { return binding_->body_a().mesh(); }

 private:
  std::shared_ptr<const Garment> garment_;
  std::size_t threads_ = 0;
  std::unique_ptr<GarmentBinding> binding_;
};

}  // namespace

PYBIND11_MODULE(_refit, m) {
  m.doc() = "The engine of the package refit (see help(refit)).";
  m.attr("__version__") = kVersion;
  python::register_errors(m);

  py::class_<Garment, std::shared_ptr<Garment>>(
      m, "Garment",
      "A garment: positions, polygon faces, `l` polylines and `p` points. read_garment() keeps the file's other "
      "lines, so write_garment() gives the file back line for line with new positions.")
      .def(py::init(&garment_from_arrays), py::arg("positions"), py::arg("face_indices"), py::arg("face_sizes"),
           py::arg("line_indices") = py::none(), py::arg("line_sizes") = py::none(),
           "A garment from arrays: positions (N x 3), the faces' vertex indices one face after another and each "
           "face's size (>= 3); lines (polylines of >= 2 vertices) the same way. InputError for an index out of range.")
      .def_property_readonly(
          "positions", [](py::object self) { return python::view(self.cast<const Garment&>().positions, self); },
          "N x 3 vertex positions (a read-only view)")
      .def_property_readonly("vertex_count", [](const Garment& g) { return g.positions.rows(); }, "N")
      .def_property_readonly("face_count", [](const Garment& g) { return g.faces.rows(); }, "Polygon faces")
      .def("__repr__", [](const Garment& g) {
        return "<refit.Garment " + std::to_string(g.positions.rows()) + " vertices, " + std::to_string(g.faces.rows()) +
               " faces>";
      });
  py::class_<BodyMesh>(m, "Body", "A body: a triangle mesh. Bodies A and B share their triangles.")
      .def(py::init(&body_from_arrays), py::arg("vertices"), py::arg("triangles"), py::arg("name") = "body",
           "A body from arrays: vertices (V x 3) and triangles (M x 3 vertex indices).")
      .def_property_readonly(
          "vertices", [](py::object self) { return python::view(self.cast<const BodyMesh&>().vertices, self); },
          "V x 3 vertex positions (a read-only view)")
      .def_property_readonly("triangle_count", [](const BodyMesh& b) { return b.triangles.size(); }, "M")
      .def_readonly("name", &BodyMesh::name, "The file's stem (names outputs and messages)")
      .def(
          "with_vertices",
          [](const BodyMesh& b, const py::array_t<double, py::array::forcecast>& v) {
            BodyMesh out = b;
            out.vertices = python::points_from(v, "with_vertices");
            if (out.vertices.rows() != b.vertices.rows())
              throw UsageError("with_vertices: " + std::to_string(out.vertices.rows()) + " vertices, the body has " +
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
      .def_property_readonly(
          "names",
          [](const Features& f) {
            std::vector<std::string> n;
            for (const FeatureSpec& s : f.specs) n.push_back(s.name);
            return n;
          },
          "The curves' names, in file order")
      .def_readonly("path", &Features::path, "The feature file")
      .def_readonly("units", &Features::units, "The garment units it was read for");
  py::class_<Result>(m, "Result", "One resize: positions (N x 3), the warp alone, the report (dict) and warnings.")
      .def_readonly("positions", &Result::positions, "N x 3: the resized garment, in the garment's vertex order")
      .def_readonly("warped", &Result::warped, "N x 3: the warp alone (step 1), for comparison")
      .def_readonly("report", &Result::report,
                    "The JSON report of `refit resize --report` as a dict: timings_ms, features (per curve "
                    "shape_error, ...), surface, collision, symmetry, metrics (with metrics=True)")
      .def_readonly("warnings", &Result::warnings, "What changed the result and should be known (list of str)");

  m.def(
      "read_garment",
      [](const std::string& path, bool keep_text) {
        py::gil_scoped_release unlocked;
        return std::make_shared<Garment>(read_garment_obj(path, keep_text ? SourceText::kept : SourceText::released));
      },
      py::arg("path"), py::arg("keep_text") = true,
      "Reads a garment OBJ (every line kept for write_garment). InputError naming file and line. keep_text=False: "
      "the file's text is not held in memory (144 MB for a 1M-vertex garment) but read again by write_garment, "
      "which raises InputError if the file changed in between.");
  m.def(
      "write_garment",
      [](const Garment& g, const py::array_t<double, py::array::forcecast>& positions, const std::string& path) {
        const Points p = python::points_from(positions, "write_garment");
        if (p.rows() != g.positions.rows())
          throw UsageError("write_garment: " + std::to_string(p.rows()) + " positions for a garment of " +
                           std::to_string(g.positions.rows()) + " vertices");
        py::gil_scoped_release unlocked;
        write_garment_obj(path, g, p);
      },
      py::arg("garment"), py::arg("positions"), py::arg("path"),
      "Writes the garment's file line for line with new v positions (a garment made from arrays: a plain OBJ), "
      "to a temporary file renamed over `path`: it appears whole or not at all.");
  m.def("keep_freed_memory", &refit::keep_freed_memory,
        "Keeps the memory a resize frees for the next one instead of handing it back to the system, for this "
        "whole process (glibc's malloc settings, as `refit resize` sets them). Call once, before large garments "
        "are read, in a process that resizes many of them: on a 1M-vertex garment each body then takes about a "
        "third less time (docs/python.md). The process keeps its largest footprint. False where it does nothing "
        "(another allocator).");
  m.def("read_body", &read_body, py::arg("path"), py::call_guard<py::gil_scoped_release>(),
        "Reads a body: .obj, .ply, .off or .stl (polygons fan-split into triangles).");
  m.def(
      "read_features",
      [](const std::string& path, const std::string& units) {
        check_units(units);
        py::gil_scoped_release unlocked;
        return Features{read_feature_file(path, units), path, units};
      },
      py::arg("path"), py::arg("units") = "cm", "Reads a feature file; `units` are the garment's (cm, mm, m or in).");
  py::class_<Binding>(m, "Binding",
                      "What depends on the garment, body A and the features, made once; resize() applies it to any "
                      "number of bodies B, from any number of Python threads at once.")
      .def(py::init([](std::shared_ptr<Garment> g, const BodyMesh& a, const Features* features, const std::string& units,
                       const std::string& stage, const std::string& symmetry, bool collision, double clearance,
                       long threads, bool metrics, const py::object& progress, double follow_body) {
             return std::make_unique<Binding>(std::move(g), a, features, units, stage, symmetry, collision, clearance,
                                              threads, metrics, progress, follow_body);
           }),
           py::arg("garment"), py::arg("body_a"), py::arg("features") = nullptr, py::arg("units") = "cm",
           py::arg("stage") = "full", py::arg("symmetry") = "auto", py::arg("collision") = true,
           py::arg("clearance") = 0.2, py::arg("threads") = 0, py::arg("metrics") = false,
           py::arg("progress") = py::none(), py::arg("follow_body") = 0.0,
           "The options of `refit resize` of the same names: features (or None); units cm|mm|m|in; stage "
           "warp|features|full; symmetry auto|x|none; collision and its clearance in cm (0 to 10); follow_body "
           "(--follow-body, cm, 0 to 10; 0: off); threads (0 = "
           "all cores; results do not depend on it); metrics adds fit, penetration and sanity metrics to the "
           "report; progress, if given, is called with each stage's name (str). UsageError for a value the command "
           "line refuses, InputError for bad input.")
      .def("resize", &Binding::resize, py::arg("body_b"), py::arg("progress") = py::none(),
           "Resizes to a body B (same triangles as body A) -> Result. InputError when they differ. progress: as "
           "for the binding.")
      .def("resize", &Binding::resize_to, py::arg("vertices"), py::arg("progress") = py::none(),
           "Resizes to body A's triangles with these vertex positions (V x 3) -> Result.")
      .def_property_readonly("body_a", &Binding::body_a, "Body A");
  m.def(
      "compare",
      [](const Garment& garment, const py::array_t<double, py::array::forcecast>& result, const BodyMesh& body_a,
         const BodyMesh& body_b, const Features* features, double fit_band) {
        const Points p = python::points_from(result, "compare");
        if (p.rows() != garment.positions.rows())
          throw UsageError("compare: " + std::to_string(p.rows()) + " positions for a garment of " +
                           std::to_string(garment.positions.rows()) + " vertices");
        nlohmann::json j;
        {
          py::gil_scoped_release unlocked;
          check_same_connectivity(body_a, body_b);
          MetricsOptions o;
          o.fit_band = fit_band;
          if (features) o.features = feature_curve_inputs(garment, p, body_a, body_b, features->specs);
          j = compute_metrics(garment, p, body_a, body_b, o).to_json();
        }
        return python::to_python(j);
      },
      py::arg("garment"), py::arg("result"), py::arg("body_a"), py::arg("body_b"), py::arg("features") = nullptr,
      py::arg("fit_band") = 1.0,
      "The metrics of `refit compare` for any resize result with the garment's vertex order (Refit's or another "
      "tool's), as a dict: fit (distance to the body, within fit_band of A), penetration (vertices inside B), sanity "
      "(NaN, flipped faces, edge-length ratios), features (shape error, turning change, straightness of each curve, "
      "result and warp alone).");
  m.def(
      "render",
      [](const BodyMesh& body, const Garment& garment, const py::object& positions, const std::string& path,
         const std::vector<std::string>& views, int width, int height, double zoom, std::pair<double, double> centre) {
        Garment shown = garment;
        if (!positions.is_none()) {
          shown.positions = python::points_from(positions.cast<py::array_t<double, py::array::forcecast>>(), "render");
          if (shown.positions.rows() != garment.positions.rows())
            throw UsageError("render: positions do not match the garment");
        }
        RenderOptions o;
        o.width = width;
        o.height = height;
        o.zoom = zoom;
        o.centre_x = centre.first;
        o.centre_y = centre.second;
        o.views.clear();
        for (const std::string& v : views) {
          if (v != "front" && v != "side" && v != "back")
            throw UsageError("views: unknown view '" + v + "' (use front, side or back)");
          o.views.push_back(parse_view(v, "views"));
        }
        Image img;
        {
          py::gil_scoped_release unlocked;
          img = refit::render(body, shown, nullptr, {}, o);
          if (!path.empty()) write_png(path, img);
        }
        py::array_t<std::uint8_t> a({img.height, img.width, 3});
        std::copy(img.rgb.begin(), img.rgb.end(), a.mutable_data());
        return a;
      },
      py::arg("body"), py::arg("garment"), py::arg("positions") = py::none(), py::arg("path") = "",
      py::arg("views") = std::vector<std::string>{"front"}, py::arg("width") = 800, py::arg("height") = 1000,
      py::arg("zoom") = 1.0, py::arg("centre") = std::pair<double, double>{0.5, 0.5},
      "Ray-traced picture of the body with the garment (at `positions` if given), one panel per view: an "
      "H x W x 3 uint8 array, also written as PNG when `path` is given (as `refit render`). `zoom` magnifies "
      "each panel about `centre` (x, y as fractions of a panel at zoom 1; refit render --zoom --centre).");
}
