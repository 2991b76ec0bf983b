// Issue 13 ("nothing sinks into the body", face interiors included) on bodies the
// shared data does not hold: MakeHuman's morphs pushed beyond the shared bodies,
// as the quality suite's --check-bodies makes them. There the body's shoulder
// poked 0.02 cm through a coarse face of the dress that five rounds of the
// collision step had not cleared. Inside is decided here by the parity of a
// vertical ray's crossings with body B's triangles (a grid over x and z), not by
// the engine's body queries. Skips when ../shared/data is absent.
#include "support/test_support.hpp"

#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

namespace refit {
namespace {

// Body A plus the weighted differences of other bodies from it (run.py's CHECK).
BodyMesh blend(const std::string& data, const std::map<std::string, double>& weights) {
  BodyMesh b = read_body(data + "/bodies/A_female.obj");
  const Points a = b.vertices;
  for (const auto& [name, w] : weights) b.vertices += w * (read_body(data + "/bodies/" + name + ".obj").vertices - a);
  return b;
}

// Whether points are inside a closed triangle mesh: an odd number of crossings
// both up (+y) and down (-y) from each point, the triangles found through a grid
// of their x-z boxes. One ray alone miscounts where it runs exactly through an
// edge shared by two triangles (both count it): 3.5 cm off the body at the shared
// dress's front hem it called two points inside.
class RayParity {
 public:
  explicit RayParity(const BodyMesh& body) : v_(body.vertices) {
    lo_ = {v_.col(0).minCoeff(), v_.col(2).minCoeff()};
    const double hx = v_.col(0).maxCoeff(), hz = v_.col(2).maxCoeff();
    cell_ = 1.0;
    nx_ = int((hx - lo_[0]) / cell_) + 1;
    nz_ = int((hz - lo_[1]) / cell_) + 1;
    cells_.resize(std::size_t(nx_) * std::size_t(nz_));
    for (const auto& tri : body.triangles) {
      double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
      for (Index i : tri) {
        x0 = std::min(x0, v_(i, 0)), x1 = std::max(x1, v_(i, 0));
        z0 = std::min(z0, v_(i, 2)), z1 = std::max(z1, v_(i, 2));
      }
      for (int i = cx(x0); i <= cx(x1); ++i)
        for (int k = cz(z0); k <= cz(z1); ++k) cells_[std::size_t(i) * nz_ + k].push_back({tri[0], tri[1], tri[2]});
    }
  }
  bool inside(const Vec3& p) const {
    if (p.x() < lo_[0] || p.z() < lo_[1] || cx(p.x()) >= nx_ || cz(p.z()) >= nz_) return false;
    int above = 0, below = 0;
    for (const auto& t : cells_[std::size_t(cx(p.x())) * nz_ + cz(p.z())]) {
      const Vec3 a = row3(v_, t[0]), b = row3(v_, t[1]), c = row3(v_, t[2]);
      // Barycentric coordinates of p's x-z in the triangle's x-z projection.
      const double det = (b.x() - a.x()) * (c.z() - a.z()) - (c.x() - a.x()) * (b.z() - a.z());
      if (det == 0.0) continue;
      const double s = ((p.x() - a.x()) * (c.z() - a.z()) - (c.x() - a.x()) * (p.z() - a.z())) / det;
      const double u = ((b.x() - a.x()) * (p.z() - a.z()) - (p.x() - a.x()) * (b.z() - a.z())) / det;
      if (s < 0.0 || u < 0.0 || s + u > 1.0) continue;
      const double y = a.y() + s * (b.y() - a.y()) + u * (c.y() - a.y());
      above += y > p.y();
      below += y < p.y();
    }
    return above % 2 == 1 && below % 2 == 1;
  }

 private:
  int cx(double x) const { return int((x - lo_[0]) / cell_); }
  int cz(double z) const { return int((z - lo_[1]) / cell_); }
  Points v_;
  std::array<double, 2> lo_{};
  double cell_ = 1.0;
  int nx_ = 0, nz_ = 0;
  std::vector<std::vector<std::array<Index, 3>>> cells_;
};

// Faces with a point inside: per fan triangle the 21 centroids of its
// subdivision into 36 (the quality suite's samples), and its corners.
std::size_t faces_inside(const Garment& g, const Points& x, const RayParity& body) {
  std::size_t count = 0;
  constexpr int m = 6;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    const auto face = g.faces.row(f);
    bool in = false;
    for (std::size_t k = 1; k + 1 < face.size() && !in; ++k) {
      const Vec3 a = row3(x, face[0]), b = row3(x, face[k]), c = row3(x, face[k + 1]);
      in = body.inside(a) || body.inside(b) || body.inside(c);
      for (int i = 0; i < m && !in; ++i)
        for (int j = 0; i + j < m && !in; ++j) {
          const double s = (i + 1.0 / 3) / m, t = (j + 1.0 / 3) / m;
          in = body.inside((1.0 - s - t) * a + s * b + t * c);
        }
    }
    count += in;
  }
  return count;
}

TEST(ClearanceSharedData, NoFaceOfTheDressesHasBodyPokingThroughOnBodiesBeyondTheShared) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: clearance test on the shared garments skipped";
  const BodyMesh body_a = read_body(data + "/bodies/A_female.obj");
  struct Case {
    const char* garment;
    const char* body;
    std::map<std::string, double> weights;
  };
  const Case cases[] = {{"dress", "F_thinnest", {{"F_thinner", 1.5}}},
                        {"outfit_dress_jeans", "F_thinnest", {{"F_thinner", 1.5}}},
                        {"dress_soup", "F_thinner_taller", {{"F_thinner", 1.0}, {"F_taller", 1.0}}}};
  for (const Case& c : cases) {
    auto garment = std::make_shared<const Garment>(read_garment_obj(data + "/garments/" + c.garment + "_on_A_female.obj"));
    const BodyMesh body_b = blend(data, c.weights);
    const RayParity parity(body_b);
    const ResizeOptions o;
    // The quality suite's features where it has them (the soup's pieces have none).
    const std::string feature_file = std::string(REFIT_SOURCE_DIR) + "/bench/quality/features/" + c.garment + ".json";
    const GarmentBinding binding(garment, body_a, o,
                                 std::string(c.garment) == "dress_soup" ? std::vector<FeatureSpec>{} : read_feature_file(feature_file));
    const ResizeResult r = binding.resize(body_b);
    const std::size_t before = faces_inside(*garment, r.warped, parity), after = faces_inside(*garment, r.positions, parity);
    const int inside_rounds = r.report.at("collision").at("inside_rounds").get<int>();
    std::printf("[ info ] %s -> %s: %zu faces with a point inside body B after the warp, %zu written (%d rounds over "
                "what was left inside)\n", c.garment, c.body, before, after, inside_rounds);
    EXPECT_GT(before, 100u) << c.garment << " -> " << c.body << ": the warp leaves faces inside";
    EXPECT_EQ(after, 0u) << c.garment << " -> " << c.body;
    EXPECT_EQ(r.report.at("collision").at("faces_inside_after").get<std::size_t>(), 0u) << c.garment;
    // The dress's shoulder face needed rounds of its own (main's five left it 0.02 cm through).
    if (std::string(c.garment) == "dress") {
      EXPECT_GE(r.report.at("collision").at("inside_rounds").get<int>(), 1);
    }
  }
}

}  // namespace
}  // namespace refit
