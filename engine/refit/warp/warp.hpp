#pragma once
// Step 1, primary resizing (paper section 3, eqs. 1-4, read with DESIGN.md).
//
// Bind once: for every point p, the nearest triangle centre q on body A, the
// triangles whose centre lies within (1+alpha)|pq| (eq. 2, capped to the
// `max_triangles` nearest of them), and p's local coordinates in each triangle's
// frame on A (eq. 3). Apply many: re-emit p from the same frames on body B,
// centred on B's triangle centres, blended with w = 1/(1e-8 + |(u,v,w)|^3) (eq. 4).
#include <refit/body/body_mesh.hpp>
#include <refit/body/centre_tree.hpp>

#include <memory>

namespace refit {

struct WarpOptions {
  double alpha = 0.2;              // eq. 2
  std::size_t max_triangles = 64;  // cap on the triangle set far from the body
};

/// What the warp of a fixed point set needs from body A: per point, its
/// triangles (CSR) and local coordinates (one row per CSR entry).
struct WarpBinding {
  Csr triangles;
  Points local;          // rows match triangles.indices
  std::size_t capped = 0;  // points whose triangle set hit max_triangles

  std::size_t size() const { return triangles.rows(); }
  /// Warped positions on a body with frames `b` (same connectivity as A).
  Points apply(const TriangleFrames& b) const;
  /// Warped position of point i alone.
  Vec3 apply_one(const TriangleFrames& b, std::size_t i) const;
};

/// Body A prepared for binding: frames and the k-d tree over valid triangle centres.
class ReferenceBody {
 public:
  explicit ReferenceBody(BodyMesh body, WarpOptions options = {});
  const BodyMesh& mesh() const { return body_; }
  const TriangleFrames& frames() const { return frames_; }
  const PointTree& centres() const { return tree_; }
  const WarpOptions& options() const { return options_; }

  /// Binds points (rows of `points`) to this body. Parallel; deterministic.
  WarpBinding bind(const Points& points) const;

 private:
  BodyMesh body_;
  WarpOptions options_;
  TriangleFrames frames_;
  PointTree tree_;
};

}  // namespace refit
