// A tighter surface solve gives the same garment, closer: the clearance rounds
// hold the agents the solve sinks at the point clear of body B nearest where
// the solve left them, and that point must not jump with the solve's last
// digits. It did (clearance.cpp): the shared skirt on F_thinner moved 0.2-0.5
// cm between tolerances 1e-6, 1e-7, ... 1e-10, one agent 0.8 cm.
// Skips when ../shared/data is absent.
#include "shared_case.hpp"

#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <gtest/gtest.h>

#include <cstdio>

namespace refit {
namespace {

TEST(ToleranceSharedData, TheSkirtConvergesAsTheSolveTightens) {
  const auto shared = test::shared_case("skirt");
  if (!shared) GTEST_SKIP() << "../shared/data is absent: real-data tolerance test skipped";
  const auto& skirt = shared->garment;
  const BodyMesh& a = shared->body_a;
  const std::vector<FeatureSpec>& features = shared->features;
  const BodyMesh b = shared->body("F_thinner");
  const auto resize = [&](double tolerance) {
    ResizeOptions o;
    o.collision = false;
    o.surface.tolerance = tolerance;
    o.surface.max_iterations = 5000;
    return GarmentBinding(skirt, a, o, features).resize(b).positions;
  };
  const Points p7 = resize(1e-7), p9 = resize(1e-9);
  const double apart = (p7 - p9).rowwise().norm().maxCoeff();
  std::printf("[ info ] skirt on F_thinner, surface tolerance 1e-7 against 1e-9: %.2e cm apart at most\n", apart);
  EXPECT_LT(apart, 1e-3);
}

}  // namespace
}  // namespace refit
