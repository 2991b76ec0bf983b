// The same garment in cm and in mm is the same resize: every length the
// pipeline compares with is in the garment's units. The surface solve's stop
// rule (the size of its update) was not, so a garment in mm was solved 10
// times tighter, and the clearance rounds held an agent where that precision
// decided (clearance.cpp): the shared skirt on F_thinner came out 0.5 cm apart.
#include "support/test_support.hpp"

#include <mannequin/mannequin.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <tuple>
#include <vector>

namespace refit {
namespace {

namespace mq = refit::mannequin;

BodyMesh scaled(BodyMesh b, double s) {
  b.vertices *= s;
  return b;
}

TEST(Units, AGarmentInMillimetresResizesAsInCentimetres) {
  const mq::BodyParams a{};
  mq::BodyParams b = a;
  b.waist *= 1.12;
  b.hip *= 1.08;
  mq::GarmentParams gp;
  gp.kind = mq::GarmentParams::Kind::Dress;
  gp.target_vertices = 4000;
  const Garment cm = mq::make_garment(a, gp);
  Garment mm = cm;
  mm.positions *= 10.0;
  const std::string json = mq::dress_features_json(a, gp);
  ResizeOptions in_cm, in_mm;
  in_mm.units = "mm";
  const ResizeResult r_cm = GarmentBinding(std::make_shared<const Garment>(cm), mq::make_body(a), in_cm,
                                           parse_feature_json(json, "dress.json", "cm"), Progress(false))
                                .resize(mq::make_body(b));
  const ResizeResult r_mm = GarmentBinding(std::make_shared<const Garment>(mm), scaled(mq::make_body(a), 10.0), in_mm,
                                           parse_feature_json(json, "dress.json", "mm"), Progress(false))
                                .resize(scaled(mq::make_body(b), 10.0));
  const auto& s_cm = r_cm.report["surface"];
  const auto& s_mm = r_mm.report["surface"];
  EXPECT_DOUBLE_EQ(s_mm["tolerance"].get<double>(), 10.0 * s_cm["tolerance"].get<double>());
  std::vector<double> d(static_cast<std::size_t>(cm.positions.rows()));
  for (Index i = 0; i < cm.positions.rows(); ++i)
    d[std::size_t(i)] = (row3(r_mm.positions, i) / 10.0 - row3(r_cm.positions, i)).norm();
  std::sort(d.begin(), d.end());
  // Scaling by 10 rounds differently, so a vertex on a threshold (eq. 14's
  // epsilon from body B, the clearance) may fall the other way: the bulk agrees.
  const double p99 = d[d.size() * 99 / 100];
  std::printf("[ info ] mm against cm, cm: median %.2e, 99th percentile %.2e, largest %.2e\n", d[d.size() / 2], p99,
              d.back());
  EXPECT_LT(p99, 1e-3);
}

// The shared skirt and dress, resized in mm against in cm. Measured: the skirt
// 0.00015 cm apart at most (0.51 cm before, 0.09 with the stop rule alone); the
// dress 0.03 cm at the 99th percentile and 0.13 at most, as before: the voxel
// sampling picks another sample for one agent near the centre back in mm, so a
// vertex on the mirror plane has another nearest agent and eq. 14 keeps it in
// one run only (without the collision step the 99th percentile is 4e-8 cm).
TEST(Units, SharedGarmentsInMillimetresResizeAsInCentimetres) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: real-data units test skipped";
  const BodyMesh a = read_body(data + "/bodies/A_female.obj"), b = read_body(data + "/bodies/F_thinner.obj");
  for (const auto& [name, limit99, limit] : {std::tuple{"skirt", 1e-3, 1e-2}, std::tuple{"dress", 0.05, 0.2}}) {
    SCOPED_TRACE(name);
    const Garment cm = read_garment_obj(data + "/garments/" + name + "_on_A_female.obj");
    Garment mm = cm;
    mm.positions *= 10.0;
    mm.source.reset();
    const std::string file = std::string(REFIT_SOURCE_DIR) + "/bench/quality/features/" + name + ".json";
    ResizeOptions in_mm;
    in_mm.units = "mm";
    const ResizeResult r_cm =
        GarmentBinding(std::make_shared<const Garment>(cm), a, {}, read_feature_file(file, "cm")).resize(b);
    const ResizeResult r_mm =
        GarmentBinding(std::make_shared<const Garment>(mm), scaled(a, 10.0), in_mm, read_feature_file(file, "mm"))
            .resize(scaled(b, 10.0));
    std::vector<double> d(static_cast<std::size_t>(cm.positions.rows()));
    for (Index i = 0; i < cm.positions.rows(); ++i)
      d[std::size_t(i)] = (row3(r_mm.positions, i) / 10.0 - row3(r_cm.positions, i)).norm();
    std::sort(d.begin(), d.end());
    const double p99 = d[d.size() * 99 / 100];
    std::printf("[ info ] %s on F_thinner, mm against cm: 99th percentile %.2e cm, largest %.2e cm\n", name, p99,
                d.back());
    EXPECT_LT(p99, limit99);
    EXPECT_LT(d.back(), limit);
  }
}

}  // namespace
}  // namespace refit
