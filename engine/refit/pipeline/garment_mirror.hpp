#pragma once
// A mirror-symmetric garment and body A, as the pipeline keeps them alike on
// both sides (issue 13, item 2): each garment vertex's mirror image about the
// plane x = c, found on the garment's own surface (meshes need not be
// vertex-symmetric), and each body A vertex's mirror partner, which tells
// whether body B is symmetric too. Lengths in the garment's units.
#include <refit/attach/attachment.hpp>
#include <refit/core/types.hpp>

#include <utility>
#include <vector>

namespace refit {

class GarmentMirror {
 public:
  /// No symmetry: active() is false and nothing may be made alike.
  GarmentMirror() = default;
  /// `images`: each garment vertex's mirror image attached to the garment, at
  /// `image_distance` from its surface (a vertex is paired when within
  /// `tolerance`); `body_a`: body A's vertices.
  GarmentMirror(double plane_x, double tolerance, SurfaceAttachment images, const std::vector<double>& image_distance,
                const Points& body_a);

  bool active() const { return !body_pairs_.empty(); }
  /// The garment's layers (`vertex_layer`, per vertex: SurfaceBinding::vertex_layers):
  /// alike_pushes() then leaves each vertex whose image lies on another layer
  /// than its own as it is.
  void set_layers(const std::vector<std::uint32_t>& vertex_layer);
  /// How many paired vertices alike_pushes() leaves as they are (set_layers).
  std::size_t pushed_apart() const { return pushed_apart_; }
  double plane_x() const { return plane_x_; }
  /// Largest distance between a body B vertex and its partner's mirror image
  /// (body B has body A's vertices), and whether that is within the tolerance.
  std::pair<double, bool> body_error(const Points& body_b) const;

  /// Each paired vertex halfway to its partner's mirror image (its image carried on `positions`);
  /// a vertex whose image lies a little beyond the tolerance part of the way (symmetrised_share).
  void symmetrise(Points& positions) const;
  /// Each paired vertex's move from `before` to `positions` becomes the mean of its own and its image's, mirrored.
  void symmetrise_moves(const Points& before, Points& positions) const;
  /// The moves from `before` to `after` made alike on both sides (see garment_mirror.cpp): new
  /// positions for the paired vertices whose push differs from its image's by more than `tolerance`.
  std::vector<std::pair<Index, Vec3>> alike_pushes(const Points& before, const Points& after, double tolerance,
                                                   double max_extra) const;

 private:
  /// Vertex i's mirror image's move (carried on the garment's faces) from `before` to `after`, mirrored.
  Vec3 mirrored_move(const Points& before, const Points& after, Index i) const;
  /// The vertices of `paired` (paired_ or pushed_alike_) whose own move from `before` to `after` or whose image's may
  /// not be zero (it or a corner of its image's face moved), with `row(i)` of each,
  /// in vertex order: a collision step or a snap moves a few of a million vertices.
  template <class Row>
  std::vector<std::pair<Index, Vec3>> paired_moving_rows(const Points& before, const Points& after, const Row& row,
                                                         const std::vector<std::uint8_t>& paired) const;

  double plane_x_ = 0.0, tolerance_ = 0.0;
  SurfaceAttachment images_;          // per garment vertex, its mirror image on the garment's surface
  std::vector<std::uint8_t> paired_;  // ... when that image is within the tolerance
  std::vector<std::uint8_t> pushed_alike_;  // ... and on the vertex's own layer (set_layers; empty: as paired_)
  std::size_t pushed_apart_ = 0;
  std::vector<Index> body_pairs_;     // per body A vertex, its mirror partner (or kNoMirror)
};

}  // namespace refit
