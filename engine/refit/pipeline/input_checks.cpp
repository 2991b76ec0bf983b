#include <refit/core/error.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/input_checks.hpp>

#include <cstdio>
#include <utility>

namespace refit {

namespace {

std::string file_of(const BodyMesh& b) { return b.path.empty() ? b.name : b.path; }
std::string file_of(const Garment& g) { return g.source ? g.source->file : "garment"; }

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

std::string units_name(double units_per_cm) {
  return units_per_cm == 1.0 ? "cm" : units_per_cm == 10.0 ? "mm" : units_per_cm == 0.01 ? "m" : "in";
}

}  // namespace

void check_human_size(const BodyMesh& body_a, double units_per_cm) {
  const double height = (body_a.vertices.colwise().maxCoeff() - body_a.vertices.colwise().minCoeff()).maxCoeff();
  const double height_cm = height / units_per_cm;
  const std::string units = units_name(units_per_cm);
  if (!(height_cm >= 30 && height_cm <= 300)) {
    std::string guess;  // the units that would make it a person
    for (const auto& [name, cm] : {std::pair{"mm", 0.1}, std::pair{"m", 100.0}, std::pair{"inches", 2.54}})
      if (height_cm * cm >= 30 && height_cm * cm <= 300) guess += guess.empty() ? std::string(" (in ") + name + "?)" : "";
    throw input_error(file_of(body_a), "body A is " + number(height) + " " + units + " tall, not a human size" + guess +
                                           ": bodies and garment need the same units, and --units names them (default cm)");
  }
}

void check_garment_on_body_a(const Garment& garment, const BodyMesh& body_a, double units_per_cm) {
  check_garment_on_body_a(garment.positions.colwise().minCoeff().transpose(), garment.positions.colwise().maxCoeff().transpose(),
                          file_of(garment), body_a, units_per_cm);
}

void check_garment_on_body_a(const Vec3& glo, const Vec3& ghi, const std::string& garment_file, const BodyMesh& body_a,
                             double units_per_cm) {
  const Vec3 lo = body_a.vertices.colwise().minCoeff().transpose(), hi = body_a.vertices.colwise().maxCoeff().transpose();
  const double height = (hi - lo).maxCoeff();
  const std::string units = units_name(units_per_cm);
  const Vec3 centre = 0.5 * (glo + ghi);
  const double margin = 0.2 * height, across = (ghi - glo).maxCoeff();
  const bool centred = (centre.array() >= lo.array() - margin).all() && (centre.array() <= hi.array() + margin).all();
  if (!centred || across > 2 * height)
    throw input_error(garment_file, "the garment (" + number(across) + " " + units + " across, centred at " +
                                           number(centre.x()) + " " + number(centre.y()) + " " + number(centre.z()) +
                                           ") does not sit on body A (" + file_of(body_a) + ", " + number(height) + " " +
                                           units + " tall): are they in the same units and place?");
}

void check_body_b_scale(const BodyMesh& body_a, const BodyMesh& body_b, const TriangleFrames& frames_b) {
  const auto height = [](const BodyMesh& b) { return (b.vertices.colwise().maxCoeff() - b.vertices.colwise().minCoeff()).maxCoeff(); };
  const double ratio = height(body_b) / height(body_a);
  if (ratio == 0) throw input_error(file_of(body_b), "body B is collapsed to one point");
  if (!(ratio >= 0.5 && ratio <= 2.0))
    throw input_error(file_of(body_b), "body B is " + number(ratio) + " times as tall as body A (" + file_of(body_a) +
                                           (ratio > 5 || ratio < 0.2 ? "): in other units? Convert it to body A's"
                                                                     : "): not the same person resized"));
  if (2 * frames_b.degenerate > frames_b.size())
    throw input_error(file_of(body_b), std::to_string(frames_b.degenerate) + " of its " + std::to_string(frames_b.size()) +
                                           " triangles have zero area: a collapsed body");
}

}  // namespace refit

namespace refit {

double estimated_memory_mb(std::size_t vertices, double agents, std::size_t body_triangles) {
  // Peaks measured on the shared skirt at 765, 28k and 113k agents (32, 54 and
  // 130 MB: 945 bytes per agent) and on the 1M and 4M dresses (560-580 bytes per
  // vertex); bench/README.md, "Memory estimate". Rounded up.
  constexpr double kBaseMb = 30, kPerVertex = 600, kPerAgent = 1000, kPerTriangle = 100;
  return kBaseMb + (kPerVertex * static_cast<double>(vertices) + kPerAgent * agents +
                    kPerTriangle * static_cast<double>(body_triangles)) / (1024.0 * 1024.0);
}

}  // namespace refit
