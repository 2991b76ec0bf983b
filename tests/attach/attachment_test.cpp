// Points bound to a garment's surface and carried to deformed states.
#include <refit/attach/attachment.hpp>

#include <gtest/gtest.h>

namespace refit {
namespace {

TEST(Attach, PointsLandOnTheirOwnFaceOfACoarseMesh) {
  // Two big quads (20 cm) and a hanging line beside them, with 200 samples
  // along one quad's diagonal: many samples share a nearest vertex that is nearer
  // another sample, the case that once attached points to far faces with a large
  // offset (which a deformation then carries rigidly).
  Garment g;
  g.positions.resize(8, 3);
  g.positions << 0, 0, 0, 20, 0, 0, 20, 20, 0, 0, 20, 0, 40, 0, 0, 40, 20, 0, 50, 0, 0, 50, 20, 0;
  g.faces.push_row(std::array<Index, 4>{0, 1, 2, 3});
  g.faces.push_row(std::array<Index, 4>{1, 4, 5, 2});
  g.lines.push_row(std::array<Index, 2>{6, 7});
  Points samples(201, 3);
  for (int i = 0; i < 200; ++i) samples.row(i) << 1.0 + 0.09 * i, 19.0 - 0.09 * i, 0.001 * (i % 3);
  samples.row(200) << 50.0, 7.0, 0.5;  // beside the hanging line
  const SurfaceAttachment at = attach_points(g, samples);
  for (Eigen::Index i = 0; i < samples.rows(); ++i) EXPECT_LT(at.offset.row(i).norm(), 0.51) << i;
  // A bend of the first quad about x = 20 moves every sample with it.
  Points bent = g.positions;
  for (int v : {0, 3}) bent(v, 2) = 20.0, bent(v, 0) = 20.0;
  bent.row(7) << 60, 20, 0;
  const Points carried = carry(at, bent);
  for (int i = 0; i < 200; ++i) {
    const double t = (samples(i, 0)) / 20.0;  // 1 at x = 20, 0 at x = 0
    EXPECT_NEAR(carried(i, 0), 20.0, 1e-9) << i;
    EXPECT_NEAR(carried(i, 2), 20.0 * (1.0 - t) + samples(i, 2), 1e-9) << i;
  }
  EXPECT_NEAR(carried(200, 0), 53.5, 1e-9);  // 7/20 of the way along the moved line
}

TEST(Attach, GarmentOfBarePointsUsesTheNearestVertex) {
  Garment g;
  g.positions.resize(3, 3);
  g.positions << 0, 0, 0, 10, 0, 0, 20, 0, 0;
  Points samples(2, 3);
  samples << 9, 1, 0, 50, 0, 0;
  const SurfaceAttachment at = attach_points(g, samples);
  Points moved = g.positions;
  moved.col(1).array() += 5.0;
  const Points carried = carry(at, moved);
  EXPECT_NEAR((carried.row(0) - Eigen::RowVector3d(9, 6, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((carried.row(1) - Eigen::RowVector3d(50, 5, 0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(at.vertex[1][0], 2);
}

}  // namespace
}  // namespace refit
