// Issue 13 ("no face folds") on a dense real garment: the shared dress split
// three times into quads through its edge midpoints (as ../shared/data's
// make_dense.py does; 135k vertices, faces of about 0.4 cm) and resized to
// F_thinner. The warp crumples it under the arms at a scale the 2 cm faces of the
// shared garments never show; the collision step smooths those folds out first
// and after each of its passes (surface/folds.hpp). Folds are counted as the
// quality suite does, not by the code under test: a face whose normal points
// against its original normal turned by the best rotation of its neighbourhood.
// Skips when ../shared/data is absent.
#include "support/test_support.hpp"

#include <refit/core/topology.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cstdio>
#include <map>

namespace refit {
namespace {

// Each n-gon split into n quads through its edge midpoints and its centroid.
Garment split_into_quads(const Garment& g) {
  std::vector<Vec3> p;
  for (Index v = 0; v < g.positions.rows(); ++v) p.push_back(row3(g.positions, v));
  std::map<std::pair<Index, Index>, Index> midpoint;
  auto mid = [&](Index a, Index b) {
    const auto key = std::minmax(a, b);
    auto [it, added] = midpoint.emplace(key, Index(p.size()));
    if (added) p.push_back(0.5 * (p[a] + p[b]));
    return it->second;
  };
  Garment out;
  std::vector<std::array<Index, 4>> quads;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    const auto face = g.faces.row(f);
    Vec3 c = Vec3::Zero();
    for (Index v : face) c += p[v];
    const Index centre = Index(p.size());
    p.push_back(c / double(face.size()));
    const std::size_t n = face.size();
    for (std::size_t i = 0; i < n; ++i)
      quads.push_back({face[i], mid(face[i], face[(i + 1) % n]), centre, mid(face[(i + n - 1) % n], face[i])});
  }
  out.positions.resize(Eigen::Index(p.size()), 3);
  for (std::size_t v = 0; v < p.size(); ++v) out.positions.row(Eigen::Index(v)) = p[v].transpose();
  for (const auto& q : quads) out.faces.push_row(q);
  return out;
}

Vec3 normal_of(const Points& p, std::span<const Index> face) {
  Vec3 n = Vec3::Zero();
  for (std::size_t i = 0; i < face.size(); ++i) n += row3(p, face[i]).cross(row3(p, face[(i + 1) % face.size()]));
  return n;
}

// Faces turned over: against their original normal turned by the best rotation
// (Umeyama) of their corners and the corners' neighbours from original to result.
std::size_t folded_faces(const Garment& g, const Points& result) {
  const Csr adjacency = vertex_adjacency(g);
  std::size_t folded = 0;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    std::vector<Index> hood;
    for (Index v : g.faces.row(f)) {
      hood.push_back(v);
      for (Index w : adjacency.row(v)) hood.push_back(w);
    }
    std::sort(hood.begin(), hood.end());
    hood.erase(std::unique(hood.begin(), hood.end()), hood.end());
    Eigen::Matrix3Xd from(3, hood.size()), to(3, hood.size());
    for (std::size_t i = 0; i < hood.size(); ++i) {
      from.col(Eigen::Index(i)) = row3(g.positions, hood[i]);
      to.col(Eigen::Index(i)) = row3(result, hood[i]);
    }
    const Eigen::Matrix3d turn = Eigen::umeyama(from, to, false).topLeftCorner<3, 3>();
    const Vec3 n0 = normal_of(g.positions, g.faces.row(f)), n1 = normal_of(result, g.faces.row(f));
    if (n0.squaredNorm() > 0.0 && n1.squaredNorm() > 0.0 && (turn * n0).dot(n1) < 0.0) ++folded;
  }
  return folded;
}

TEST(FoldsSharedData, TheDenseDressComesOutWithoutTheWarpsFolds) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: dense dress fold test skipped";
  Garment dense = read_garment_obj(data + "/garments/dress_on_A_female.obj");
  for (int round = 0; round < 3; ++round) dense = split_into_quads(dense);
  ASSERT_GT(dense.vertex_count(), 130000u);
  auto garment = std::make_shared<const Garment>(std::move(dense));
  const std::vector<FeatureSpec> features =
      read_feature_file(std::string(REFIT_SOURCE_DIR) + "/bench/quality/features/dress.json");
  const BodyMesh body_a = read_body(data + "/bodies/A_female.obj"), body_b = read_body(data + "/bodies/F_thinner.obj");
  std::size_t folds[2];
  for (const bool smooth : {false, true}) {
    ResizeOptions o;
    o.smooth_folds = smooth;
    const GarmentBinding binding(garment, body_a, o, features);
    const ResizeResult r = binding.resize(body_b);
    folds[smooth] = folded_faces(*garment, r.positions);
    EXPECT_EQ(r.report.at("collision").at("inside_after").get<std::size_t>(), 0u);
    if (smooth) {
      const auto& report = r.report.at("collision").at("folds");
      EXPECT_LT(report.at("left"), report.at("folded"));
    }
  }
  std::printf("[ info ] dense dress -> F_thinner: %zu faces folded with --keep-folds, %zu smoothed out first\n", folds[0],
              folds[1]);
  EXPECT_GE(folds[0], 100u);  // the problem is there ...
  // ... and gone: before the slivers the smoothing leaves were reshaped and the
  // folds smoothed again after the second symmetric pass, 4 were left (under the bust).
  EXPECT_EQ(folds[1], 0u);
}

}  // namespace
}  // namespace refit
