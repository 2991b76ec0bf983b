// GarmentMirror: the collision step's pushes made alike only between a vertex
// and a mirror image on its own layer.
#include <refit/pipeline/garment_mirror.hpp>

#include <gtest/gtest.h>

#include <algorithm>

namespace refit {
namespace {

// Two layers, mirror-symmetric about x = 0 except the outer one's right vertex,
// which stands farther out: the outer left vertex's mirror image lies nearer
// the inner layer (as the real dress's top over its skirt at the front waist).
//   0: outer, left (-1, 0, 1)     image: 2 (inner, right), the nearer surface
//   1: outer, right (1, 0, 1.8)   image: 0
//   2: inner, right (1, 0, 0.5)   image: 3
//   3: inner, left (-1, 0, 0.5)   image: 2
GarmentMirror two_layer_mirror(Points& positions) {
  positions.resize(4, 3);
  positions << -1, 0, 1, 1, 0, 1.8, 1, 0, 0.5, -1, 0, 0.5;
  SurfaceAttachment images;
  const Index image_of[] = {2, 0, 3, 2};
  images.offset.setZero(4, 3);
  for (Index v = 0; v < 4; ++v) {
    images.vertex.push_back({image_of[v], image_of[v], image_of[v]});
    images.weight.push_back({1.0, 0.0, 0.0});
    Vec3 mirrored = row3(positions, v);
    mirrored.x() = -mirrored.x();
    images.offset.row(v) = (mirrored - row3(positions, image_of[v])).transpose();
  }
  const std::vector<double> distance = offset_lengths(images);
  Points body_a(2, 3);
  body_a << -1, 0, 0, 1, 0, 0;
  return GarmentMirror(0.0, 1.0, std::move(images), distance, body_a);
}

// The body pushes the inner layer out on the right only (after the collision
// step's rounds): which vertices does alike_pushes move?
std::vector<Index> pushed_alike(const GarmentMirror& mirror, const Points& before) {
  Points after = before;
  after(2, 2) += 0.3;
  std::vector<Index> moved;
  for (const auto& [i, p] : mirror.alike_pushes(before, after, 0.01, 0.1)) moved.push_back(i);
  return moved;
}

TEST(GarmentMirror, APushIsMadeAlikeOnlyWithAnImageOnTheVertexsOwnLayer) {
  Points positions;
  GarmentMirror mirror = two_layer_mirror(positions);
  ASSERT_TRUE(mirror.active());
  // Without layers: the outer left vertex takes the inner right one's push.
  const std::vector<Index> before_layers = pushed_alike(mirror, positions);
  EXPECT_NE(std::find(before_layers.begin(), before_layers.end(), 0), before_layers.end());

  mirror.set_layers({1, 1, 2, 2});
  EXPECT_EQ(mirror.pushed_apart(), 1u);
  const std::vector<Index> moved = pushed_alike(mirror, positions);
  EXPECT_EQ(std::find(moved.begin(), moved.end(), 0), moved.end()) << "the outer layer took the inner one's push";
  // The inner layer's own pair still moves alike: its left vertex takes half the right one's push.
  EXPECT_NE(std::find(moved.begin(), moved.end(), 3), moved.end());
}

TEST(GarmentMirror, TheSymmetrisationStillUsesAnImageOnAnotherLayer) {
  Points positions;
  GarmentMirror mirror = two_layer_mirror(positions);
  mirror.set_layers({1, 1, 2, 2});
  // The surface step's symmetrisation: vertex 0 moves with the surface around its image.
  Points moved = positions;
  moved(2, 2) += 0.4;
  Points symmetrised = moved;
  mirror.symmetrise(symmetrised);
  EXPECT_NEAR(symmetrised(0, 2) - positions(0, 2), 0.2, 1e-12);
}

// A vertex whose image lies 1.5 times the tolerance off the garment moves half
// as far to the mean as a paired one; at twice the tolerance, not at all.
TEST(GarmentMirror, TheSymmetrisationEasesOffBeyondTheTolerance) {
  for (const double off : {0.0, 1.5, 2.0}) {
    SCOPED_TRACE(off);
    Points positions(2, 3);
    positions << -1, 0, 0, 1, 0, 0;
    SurfaceAttachment images;
    images.vertex = {{1, 1, 1}, {0, 0, 0}};
    images.weight = {{1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}};
    images.offset.setZero(2, 3);
    images.offset(0, 2) = off;  // vertex 0's image stands `off` in front of vertex 1
    const GarmentMirror mirror(0.0, 1.0, std::move(images), {off, 0.0}, positions);
    Points moved = positions;
    moved(1, 1) += 0.4;  // vertex 1 rises; vertex 0 stays
    mirror.symmetrise(moved);
    const double expected = off <= 1.0 ? 0.2 : off < 2.0 ? 0.1 : 0.0;  // half the way at 1.5 times the tolerance
    EXPECT_NEAR(moved(0, 1), expected, 1e-12);
  }
}

}  // namespace
}  // namespace refit
