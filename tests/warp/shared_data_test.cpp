// The warp on real MakeHuman data (../shared/data): the dress from the reference
// body to every target body. Skips when the data is absent.
#include "support/test_support.hpp"

#include <refit/body/body_surface.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/warp/warp.hpp>

#include <gtest/gtest.h>

namespace refit {
namespace {

TEST(WarpSharedData, DressToEveryTargetBodyKeepsNearVerticesNear) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: real-data warp test skipped";
  const Garment dress = read_garment_obj(data + "/garments/dress_on_A_female.obj");
  const BodyMesh a = read_body(data + "/bodies/A_female.obj");
  const BodySurface surface_a(a);
  std::vector<Index> near;
  for (Index i = 0; i < dress.vertex_count(); ++i)
    if (surface_a.closest(row3(dress.positions, i)).distance <= 1.0) near.push_back(i);
  ASSERT_GT(near.size(), dress.vertex_count() / 4) << "most of the dress should hug body A";

  const ReferenceBody ref(a);
  const WarpBinding binding = ref.bind(dress.positions);
  for (const char* target : {"F_heavier", "F_thinner", "F_taller"}) {
    SCOPED_TRACE(target);
    const BodyMesh b = read_body(data + "/bodies/" + target + ".obj");
    check_same_connectivity(a, b);
    const Points out = binding.apply(compute_frames(b));
    ASSERT_EQ(out.rows(), dress.positions.rows());
    ASSERT_TRUE(out.allFinite());
    const BodySurface surface_b(b);
    std::size_t far = 0;
    double worst = 0.0, change = 0.0;
    for (Index i : near) {
      const double d = surface_b.closest(row3(out, i)).distance;
      worst = std::max(worst, d);
      change = std::max(change, std::abs(d - surface_a.closest(row3(dress.positions, i)).distance));
      far += d > 1.0 ? 1 : 0;
    }
    std::printf("%s: worst %.4f cm, largest clearance change %.4f cm, %zu beyond 1 cm\n", target, worst, change, far);
    // The warp keeps a near vertex's clearance to within 1 mm: so vertices just
    // inside the 1 cm band can end just outside it (on F_thinner, 3 vertices at
    // 0.995 cm end at up to 1.031 cm). The bound below is that, not a looser 1 cm.
    EXPECT_LE(change, 0.1) << "clearance of a near vertex changed by more than 1 mm on " << target;
    EXPECT_LE(worst, 1.1) << far << " of " << near.size() << " near vertices end farther than 1 cm from " << target;
  }
}

}  // namespace
}  // namespace refit
