// `refit render`: a headless ray-traced picture of a body with one or two
// garments side by side, feature curves on top.
#include "command.hpp"

#include <refit/io/atomic_file.hpp>

#include <refit/core/error.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/metrics/render.hpp>

#include <cstdio>
#include <memory>
#include <sstream>

namespace refit::cli {
namespace {

struct RenderArgs {
  std::string body, garment, garment2, curves, out, views = "front", size = "800x1000", labels, title, centre = "0.5,0.5";
  double zoom = 1.0;
};

// Two numbers joined by `sep` and nothing else ("800x1000", "0.4,0.55").
template <class T>
bool read_pair(const std::string& text, char sep, T& first, T& second) {
  std::istringstream in(text);
  char got = 0, extra = 0;
  return (in >> first >> got >> second) && got == sep && !(in >> extra);
}

RenderOptions parse_options(const RenderArgs& a) {
  RenderOptions o;
  if (!read_pair(a.size, 'x', o.width, o.height))
    throw Error("--size: expected WIDTHxHEIGHT (e.g. 800x1000), got '" + a.size + "'");
  o.views.clear();
  std::stringstream vs(a.views);
  for (std::string v; std::getline(vs, v, ',');) o.views.push_back(parse_view(v));
  std::stringstream ls(a.labels);
  for (std::string l; std::getline(ls, l, ',');) o.labels.push_back(l);
  o.title = a.title;
  o.zoom = a.zoom;
  if (!read_pair(a.centre, ',', o.centre_x, o.centre_y))
    throw Error("--centre: expected X,Y as fractions of a panel (e.g. 0.4,0.55), got '" + a.centre + "'");
  return o;
}

// Feature curves as drawn: the `l` polylines of an OBJ (e.g. resize --curves-out).
std::vector<Points> read_curves(const std::string& path) {
  std::vector<Points> curves;
  if (path.empty()) return curves;
  const Garment g = read_garment_obj(path);
  for (std::size_t r = 0; r < g.lines.rows(); ++r) {
    const auto line = g.lines.row(r);
    Points c(static_cast<Eigen::Index>(line.size()), 3);
    for (std::size_t k = 0; k < line.size(); ++k) c.row(static_cast<Eigen::Index>(k)) = g.positions.row(line[k]);
    curves.push_back(std::move(c));
  }
  if (curves.empty()) throw input_error(path, "has no `l` polylines to draw");
  return curves;
}

int run(const RenderArgs& a) {
  const RenderOptions options = parse_options(a);
  std::vector<std::string> inputs = {a.body, a.garment};
  if (!a.garment2.empty()) inputs.push_back(a.garment2);
  if (!a.curves.empty()) inputs.push_back(a.curves);
  check_outputs(inputs, {a.out});  // before the work: a wrong --out fails at once
  const BodyMesh body = read_body(a.body);
  const Garment garment = read_garment_obj(a.garment);
  std::unique_ptr<Garment> second;
  if (!a.garment2.empty()) second = std::make_unique<Garment>(read_garment_obj(a.garment2));
  const Image img = render(body, garment, second.get(), read_curves(a.curves), options);
  write_png(a.out, img);
  std::printf("wrote %s (%dx%d)\n", a.out.c_str(), img.width, img.height);
  return 0;
}

const Register render_command("render", "ray-traced PNG of a body with one or two garments side by side",
                   [](CLI::App& app) -> std::function<int()> {
                     auto args = std::make_shared<RenderArgs>();
                     app.add_option("--body", args->body, "body mesh")->required();
                     app.add_option("--garment", args->garment, "garment OBJ (left half)")->required();
                     app.add_option("--garment2", args->garment2, "second garment OBJ (right half)");
                     app.add_option("--features-out", args->curves, "feature curves OBJ (`l` polylines) to draw on top");
                     app.add_option("--out", args->out, "PNG to write")->required();
                     app.add_option("--views", args->views, "comma-separated views: front, side, back (default front)");
                     app.add_option("--size", args->size, "picture size WIDTHxHEIGHT (default 800x1000)");
                     app.add_option("--labels", args->labels, "comma-separated labels over the garments, e.g. 'warp alone,Refit'");
                     app.add_option("--title", args->title, "title across the top, e.g. the body's name");
                     app.add_option("--zoom", args->zoom, "magnify every panel (1 to 1000; default 1: the whole body)");
                     app.add_option("--centre,--center", args->centre,
                                    "with --zoom: the point to magnify about, X,Y as fractions of a panel at zoom 1 "
                                    "(0,0 top left; default 0.5,0.5)");
                     return [args] { return run(*args); };
                   });

}  // namespace
}  // namespace refit::cli
