#pragma once
// How the surface step samples a garment (select_agents, agents.hpp): the
// samples of each face and `l` segment, and the key that elects the sample
// nearest its voxel's centre. Shared by select_agents and the chunked mode
// (refit/chunked), which must elect the same agents.
#include <refit/core/types.hpp>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <tuple>

namespace refit::sampling {

inline double tri_area(const Vec3& a, const Vec3& b, const Vec3& c) { return 0.5 * (b - a).cross(c - a).norm(); }

/// Subdivision of a triangle (m^2 sub-triangles, one sample at each centroid) so
/// that a sub-triangle's area is at most (h/2)^2 / 2. Triangles far smaller than a
/// sample spacing get none: their corners (vertex samples) already cover them.
inline std::uint32_t face_subdivision(double area, double spacing) {
  const double m = std::sqrt(2.0 * area) / spacing;
  if (m < 0.5) return 0;
  return static_cast<std::uint32_t>(std::ceil(m));
}

inline std::uint32_t segment_samples(double length, double spacing) {
  const double m = length / spacing;
  if (m < 0.5) return 0;
  return static_cast<std::uint32_t>(std::ceil(m));
}

/// The k-th of the m^2 centroids of a triangle subdivided m times: barycentric weights.
inline std::array<double, 3> lattice_point(std::uint32_t m, std::uint32_t k) {
  // Row r holds 2r+1 sub-triangles (r up triangles, r+1... ): walk rows.
  std::uint32_t r = static_cast<std::uint32_t>(std::sqrt(static_cast<double>(k)));
  while (r * r > k) --r;
  while ((r + 1) * (r + 1) <= k) ++r;
  const std::uint32_t j = k - r * r;  // 0 .. 2r within row r
  // Coordinates on the lattice (s along edge 01, t along edge 02), in units of 1/m.
  double s, t;
  const std::uint32_t q = j / 2;
  if (j % 2 == 0) {  // upward sub-triangle (q, r-q), (q+1, r-q), (q, r-q+1) in (s, t)
    s = q + 1.0 / 3.0;
    t = (r - q) + 1.0 / 3.0;
  } else {  // downward sub-triangle
    s = q + 2.0 / 3.0;
    t = (r - q - 1) + 2.0 / 3.0;
  }
  s /= m;
  t /= m;
  return {1.0 - s - t, s, t};
}

/// A sample as (vertices, weights).
struct Sample {
  std::array<Index, 3> v;
  std::array<double, 3> w;
};

/// A sample's position on `a`, `b`, `c` (its vertices' positions).
inline Vec3 sample_position(const Sample& s, const Vec3& a, const Vec3& b, const Vec3& c) {
  return Vec3(s.w[0] * a + s.w[1] * b + s.w[2] * c);
}

struct SampleKey {
  std::uint64_t voxel;
  std::uint64_t rank;  // float bits of squared distance to the voxel centre, then sample number
  std::uint32_t layer;
  bool operator<(const SampleKey& o) const {
    return std::tie(voxel, layer, rank) < std::tie(o.voxel, o.layer, o.rank);
  }
};

}  // namespace refit::sampling
