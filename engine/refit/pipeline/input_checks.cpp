#include <refit/pipeline/input_checks.hpp>

#include <refit/body/body_surface.hpp>  // closest_point_on_triangle
#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/obj_garment.hpp>

#include <algorithm>
#include <cstdio>
#include <limits>
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

std::vector<Index> depth_check_sample(std::size_t vertex_count) {
  constexpr std::size_t kSamples = 4096;
  const std::size_t step = std::max<std::size_t>(1, vertex_count / kSamples);
  std::vector<Index> ids;
  for (std::size_t v = 0; v < vertex_count; v += step) ids.push_back(Index(v));
  return ids;
}

void check_garment_over_body_a(const Points& sample, const Vec3& lo, const Vec3& hi, const std::string& garment_file,
                               const BodyMesh& body_a, double units_per_cm) {
  const double height = (body_a.vertices.colwise().maxCoeff() - body_a.vertices.colwise().minCoeff()).maxCoeff();
  const double across = (hi - lo).maxCoeff();
  const std::string units = units_name(units_per_cm);
  if (across < 0.01 * height)
    throw input_error(garment_file, "the garment is " + number(across) + " " + units + " across, a dot beside body A (" +
                                        file_of(body_a) + ", " + number(height) + " " + units +
                                        " tall): is it in the same units as the bodies?");
  // Depth from the closest point on the triangles whose centres are nearest, on
  // the inner side of its triangle (the body's winding taken from the sign of its
  // volume): a tenth of the time of building body A's surface (40 ms), and exact
  // enough to tell a garment fitted over the body from one a third inside it.
  const auto& x = body_a.vertices;
  const std::size_t nt = body_a.triangles.size();
  Points centre(Eigen::Index(nt), 3);
  std::vector<Vec3> normal(nt);
  double volume = 0.0;
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tri = body_a.triangles[t];
    const Vec3 a = row3(x, tri[0]), b = row3(x, tri[1]), c = row3(x, tri[2]);
    centre.row(Eigen::Index(t)) = ((a + b + c) / 3.0).transpose();
    normal[t] = (b - a).cross(c - a);
    volume += a.dot(b.cross(c));
  }
  const double outward = volume < 0.0 ? -1.0 : 1.0;
  const PointTree centres(centre);
  const double depth = 0.01 * height;
  const std::size_t n = std::size_t(sample.rows());
  std::vector<std::uint8_t> deep(n, 0);
  parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
    std::vector<Index> near;
    std::vector<double> d2;
    for (std::size_t k = b; k < e; ++k) {
      const Vec3 p = row3(sample, Index(k));
      centres.knn(p, 8, near, d2);
      double best = std::numeric_limits<double>::infinity();
      bool behind = false;
      for (Index t : near) {
        const auto& tri = body_a.triangles[t];
        const Vec3 q = closest_point_on_triangle(p, row3(x, tri[0]), row3(x, tri[1]), row3(x, tri[2]));
        if (const double d = (p - q).norm(); d < best) best = d, behind = outward * (p - q).dot(normal[t]) < 0.0;
      }
      deep[k] = behind && best > depth;
    }
  });
  const std::size_t count = std::size_t(std::count(deep.begin(), deep.end(), 1));
  if (3 * count > n)
    throw input_error(garment_file, number(100.0 * double(count) / double(n)) + " % of its vertices (" +
                                        std::to_string(count) + " of " + std::to_string(n) + " tested) are more than " +
                                        number(depth) + " " + units + " inside body A (" + file_of(body_a) +
                                        "): is the garment in the same units as the bodies, and fitted over body A?");
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
