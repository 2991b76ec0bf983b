// Embeds Refit: binds a point to a one-triangle body A and warps it to a body B
// moved by (1, 2, 3); the point must move by the same amount.
#include <refit/pipeline/resize.hpp>

#include <cmath>
#include <cstdio>

int main() {
  refit::BodyMesh a;
  a.name = "A";
  a.vertices.resize(3, 3);
  a.vertices << 0, 0, 0, 10, 0, 0, 0, 10, 0;
  a.triangles.push_back({0, 1, 2});
  refit::BodyMesh b = a;
  b.name = "B";
  b.vertices.rowwise() += Eigen::RowVector3d(1, 2, 3);

  auto garment = std::make_shared<refit::Garment>();
  garment->positions.resize(1, 3);
  garment->positions << 3, 3, 1;
  garment->points.push_row(std::vector<refit::Index>{0});
  refit::ResizeOptions options;
  options.stage = refit::Stage::Warp;
  const refit::GarmentBinding binding(garment, a, options);
  const refit::ResizeResult r = binding.resize(b);
  const double err = (r.positions.row(0) - Eigen::RowVector3d(4, 5, 4)).norm();
  std::printf("refit consumer: moved to (%g, %g, %g), error %g\n", r.positions(0, 0), r.positions(0, 1),
              r.positions(0, 2), err);
  return err < 1e-9 ? 0 : 1;
}
