#pragma once
// Small closed test bodies shared by the suites.
#include <refit/body/body_mesh.hpp>

namespace refit::test {

/// Subdivided icosahedron: vertices on the sphere, outward triangles, closed.
BodyMesh icosphere(int levels, double radius, const Vec3& centre = Vec3::Zero());

}  // namespace refit::test
