#pragma once
// Step 1, primary resizing (paper section 3, eqs. 1-4, read with DESIGN.md). Lengths in the garment's units;
// a binding is read-only once made, and apply() runs in parallel with the same bits for any thread count.
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
  double alpha = 0.2;  // eq. 2
  /// Cap on the triangle set far from the body (the K nearest inside eq. 2's
  /// radius). Vertices within a few cm of body A never reach it (on the MakeHuman
  /// dress the clearance of every vertex within 1 cm of the body is the same for
  /// K = 8 to 64), so it only shapes loose parts, where a set that hits the cap
  /// changes by one triangle of K from vertex to vertex and the warped surface gets
  /// small kinks: plainly visible at K = 8 to 16 on the A-line skirt of the
  /// procedural dress, faint at 32, about as at 64 to 128 (99.9th percentile of
  /// |log edge stretch| 1.95, 1.40, 1.47, 1.36, 1.28 for K = 8, 16, 32, 64, 128:
  /// eq. 2's own radius cut is discontinuous too). Bind time at 1M vertices
  /// grows about linearly with K (1 thread: 0.62 s at 16, 0.95 s at 32, 1.46 s at
  /// 64), apply time with the set size. 32 is the default: most of the quality of
  /// 64 at two thirds of the cost (bench/README.md has the numbers).
  std::size_t max_triangles = 32;
};

/// What every warp to one body B needs per triangle of body A: M = F_B F_A^T (a
/// point's local coordinates on A re-emitted on B are c_B + M (p - c_A)) and
/// whether the triangle moved at all. Made once per body B for any number of
/// WarpBinding::apply calls (the garment, each feature curve, each chunk).
struct TriangleChange {
  const TriangleFrames* a = nullptr;  // body A's frames (the bindings' reference)
  const TriangleFrames* b = nullptr;  // body B's
  std::vector<double> m;              // 9 per triangle, row-major
  std::vector<std::uint8_t> moved;
};
/// Throws refit::Error when the bodies' triangle counts differ. Keeps pointers to both.
TriangleChange triangle_change(const TriangleFrames& a, const TriangleFrames& b);

/// What the warp of a fixed point set needs from body A: the points, and per
/// point its triangle set (CSR, nearest first). Local coordinates are not
/// stored: frames are orthonormal, so u_i*u' + v_i*v' + w_i*w' = M_i (p - c_i)
/// with M_i = F'_i F_i^T, and |(u_i, v_i, w_i)| = |p - c_i|; apply forms M_i once
/// per triangle. This keeps a binding at 4 bytes per (point, triangle) pair.
struct WarpBinding {
  Points points;                                     // bound positions around body A
  Csr triangles;                                     // per point: eq. 2 set, capped
  std::shared_ptr<const TriangleFrames> reference;   // body A's frames
  std::size_t capped = 0;                            // points whose set hit max_triangles

  std::size_t size() const { return triangles.rows(); }
  /// Warped positions (eq. 4) on a body whose frames are `b` (same connectivity
  /// as A). Triangles degenerate on B are left out of the blend; a point whose
  /// whole set is degenerate on B follows its nearest triangle's centre.
  Points apply(const TriangleFrames& b) const;
  /// The same with the change to body B made once (its `a` must be this binding's reference).
  Points apply(const TriangleChange& change) const;
};

/// Body A prepared for binding: frames and the k-d tree over valid triangle centres.
class ReferenceBody {
 public:
  explicit ReferenceBody(BodyMesh body, WarpOptions options = {});
  const BodyMesh& mesh() const { return body_; }
  const TriangleFrames& frames() const { return *frames_; }
  const PointTree& centres() const { return tree_; }
  const WarpOptions& options() const { return options_; }

  /// Binds points (rows of `points`) to this body. Parallel; deterministic.
  WarpBinding bind(const Points& points) const;

 private:
  BodyMesh body_;
  WarpOptions options_;
  std::shared_ptr<const TriangleFrames> frames_;
  PointTree tree_;
};

}  // namespace refit
