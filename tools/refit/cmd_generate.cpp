// `refit generate`: the procedural mannequin and garments as files, for trying
// the engine and for the benchmarks' large garments.
#include "body_options.hpp"
#include "command.hpp"

#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>

namespace refit::cli {
namespace {

struct GenerateArgs {
  mannequin::BodyParams body;
  std::string kind = "dress", body_out, garment_out, features_out;
  std::size_t vertices = 20000;
  double ease = 0;
  bool soup = false, two_layers = false;
};

mannequin::GarmentParams::Kind parse_kind(const std::string& k) {
  using K = mannequin::GarmentParams::Kind;
  if (k == "dress") return K::Dress;
  if (k == "top") return K::Top;
  if (k == "trousers") return K::Trousers;
  throw Error("--kind: unknown garment '" + k + "' (use dress, top or trousers)");
}

int run(const GenerateArgs& a) {
  if (a.body_out.empty() && a.garment_out.empty() && a.features_out.empty())
    throw Error("nothing to write: give --body-out, --garment-out and/or --features-out");
  mannequin::GarmentParams g;
  g.kind = parse_kind(a.kind);
  g.target_vertices = a.vertices;
  g.ease = a.ease;
  g.soup = a.soup;
  g.two_layers = a.two_layers;
  std::vector<std::string> outs;
  for (const std::string* out : {&a.body_out, &a.garment_out, &a.features_out})
    if (!out->empty()) outs.push_back(*out);
  check_outputs({}, outs);
  OutputBatch together;
  if (!a.body_out.empty()) write_body_obj(a.body_out, mannequin::make_body(a.body));
  if (!a.garment_out.empty()) write_garment_obj(a.garment_out, mannequin::make_garment(a.body, g));
  if (!a.features_out.empty()) {
    const std::string json = mannequin::dress_features_json(a.body, g);
    write_file_atomically(a.features_out, [&](std::ostream& out) { out << json; });
  }
  together.commit();
  return 0;
}

const Register generate_command("generate", "Write a procedural mannequin, garment and feature file", [](CLI::App& app) {
  auto a = std::make_shared<GenerateArgs>();
  add_body_options(app, a->body);
  app.add_option("--resolution", a->body.resolution, "Body resolution (1: about 26k triangles)")->capture_default_str();
  app.add_option("--kind", a->kind, "Garment: dress, top or trousers")->capture_default_str();
  app.add_option("--vertices", a->vertices, "Garment vertex count (approximate)")->capture_default_str();
  app.add_option("--ease", a->ease, "Extra ease in cm")->capture_default_str();
  app.add_flag("--soup", a->soup, "Emit the garment as a non-manifold polygon soup");
  app.add_flag("--two-layers", a->two_layers, "Two layers in one garment");
  app.add_option("--body-out", a->body_out, "Write the body OBJ");
  app.add_option("--garment-out", a->garment_out, "Write the garment OBJ");
  app.add_option("--features-out", a->features_out, "Write the dress's feature file (JSON)");
  return [a]() { return run(*a); };
});

}  // namespace
}  // namespace refit::cli
