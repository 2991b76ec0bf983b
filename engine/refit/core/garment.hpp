#pragma once
// The garment data model: positions SoA plus polygon faces, polylines (`l`) and points (`p`) in CSR form, in
// the file's own units (nothing converts them). Faces may be of any size and non-manifold; vertices may be used
// by nothing. `source` keeps the original file text so a writer can give the file back line for line with only
// the positions changed. A plain value: read it from any number of threads, change it from one.
#include <refit/core/types.hpp>

#include <memory>
#include <span>
#include <string>

namespace refit {

struct ObjSource;  // defined in <refit/io/obj_garment.hpp>

struct Garment {
  Points positions;  // n x 3
  Csr faces;         // polygon corners (vertex indices), any size >= 3
  Csr lines;         // `l` polylines, >= 2 vertices each
  Csr points;        // `p` elements, >= 1 vertex each
  std::shared_ptr<const ObjSource> source;  // null for generated garments

  std::size_t vertex_count() const { return static_cast<std::size_t>(positions.rows()); }
};

/// Newell normal of a face (twice its area for a planar face, not normalised;
/// zero for a degenerate face or fewer than 3 corners' worth of area).
inline Vec3 face_normal(const Points& positions, std::span<const Index> face) {
  Vec3 n = Vec3::Zero();
  for (std::size_t k = 0; k < face.size(); ++k) n += row3(positions, face[k]).cross(row3(positions, face[(k + 1) % face.size()]));
  return n;
}

}  // namespace refit
