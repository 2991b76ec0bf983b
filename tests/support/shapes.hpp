#pragma once
// Small closed test bodies shared by the suites.
#include <refit/body/body_mesh.hpp>
#include <refit/core/garment.hpp>

#include <functional>

namespace refit::test {

/// Subdivided icosahedron: vertices on the sphere, outward triangles, closed.
BodyMesh icosphere(int levels, double radius, const Vec3& centre = Vec3::Zero());

// The same sphere as a garment (a closed shell of triangles).
Garment icosphere_garment(int levels, double radius);

/// A quad grid of nx x nz vertices, spacing s, on y = height(x, z), starting at (x0, z0).
Garment quad_grid(int nx, int nz, double s, const std::function<double(double, double)>& height, double x0 = 0.0,
                  double z0 = 0.0);

/// b's faces, lines and points appended to a's (b's vertex indices shifted).
Garment merge_garments(const Garment& a, const Garment& b);

}  // namespace refit::test
