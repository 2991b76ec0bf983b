#pragma once
// Penetration resolution (beyond the paper; runs after the surface step): garment
// vertices inside body B or closer than a clearance, and the corners of faces
// with an interior point that is, move out along the body's closest-point
// normal, and the correction is spread smoothly over their neighbours so no
// spikes appear; vertices near the body are lifted by at most what they need.
// Units: the garment's (CollisionOptions' lengths; the pipeline converts its
// cm defaults). Threads: parallel inside, the same bits for any thread count.
#include <refit/body/body_surface.hpp>
#include <refit/collision/layer_order.hpp>
#include <refit/core/garment.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

namespace refit {

struct CollisionOptions {
  double clearance = 0.2;       // garment units (0.2 cm)
  int smoothing_rings = 6;      // how far (in edges) a correction spreads
  /// Rounds after the first repair what the last one left (on the 1M dress on
  /// F_heavier: 237, then 8 and 2 vertices, a rounding error short not counted).
  /// Each such correction spreads over
  /// as many rings as keep its tilt of the surface under this (its amount over
  /// rings times the vertex's mean edge length), at most smoothing_rings;
  /// 0: always smoothing_rings.
  double repair_tilt = 0.02;
  int smoothing_passes = 12;    // Jacobi passes of the displacement field
  int max_rounds = 5;           // re-check and repeat while something is still too close
  /// Then, at most this many more over what is still inside (vertices, faces'
  /// corners). The real outfit on a body 1.5x thinner (F_thinnest) needs 12 since
  /// the dress no longer takes the jeans' pushes (GarmentMirror::set_layers);
  /// rounds run only while something is inside.
  int inside_rounds = 16;
  double near_band = 1.0;       // garment units: vertices this close to body B (before the step) are lifted off it
  double max_lift = 0.1;        // by at most this beyond what they need (0 band: no limit)
  double face_clearance = 0.05; // garment units: what points inside faces keep from body B
  /// Garment units: a face wider than this (its farthest corner from its centre)
  /// also keeps the points of it over body B's vertices nearby clear; a smaller
  /// face's samples lie too close together for a smooth body to rise between them
  /// by more than face_clearance.
  double probe_radius = 0.25;
  int unfold_passes = 20;       // passes that undo a correction turning a face over (see collision.cpp)
  /// Per vertex (or null): vertices the spread of other vertices' corrections
  /// must not move (the corners of the faces the feature curves sit on, so the
  /// written garment keeps passing through the curves). A pinned vertex that is
  /// itself inside body B or too close still moves out.
  const std::vector<std::uint8_t>* pinned = nullptr;
  /// Optional: after the rounds, new positions for some vertices (given the
  /// positions then), e.g. both sides of a mirror-symmetric garment moved alike,
  /// or the folds the pushes made smoothed out;
  /// the rounds then run again over those vertices, so what it leaves too close
  /// is pushed out by what it still needs.
  std::function<std::vector<std::pair<Index, Vec3>>(const Points& positions)> after_rounds;
  /// The hook and the round after it, at most this many times (while the hook
  /// moves something): the pipeline's symmetric pushes leave a pair apart by
  /// what that round pushes out on one side only, and a second pass halves it.
  int after_rounds_passes = 1;
  /// Optional: the garment's vertex_adjacency (core/topology.hpp), for a caller
  /// that resolves one garment on many bodies (on a 1M garment it takes 0.1 s
  /// to make); null: made here.
  const Csr* adjacency = nullptr;
  /// Optional: the garment's vertex_faces (core/topology.hpp), for the same
  /// caller: the rounds that check few vertices ask only their faces. Null:
  /// made here when the first such round needs it.
  const Csr* faces_of_vertex = nullptr;
  /// Optional: where a layer lies over another in the input (bind_layer_order):
  /// each outer point is kept its `keep` over its inner vertex, its triangle's
  /// corners pushed outward (spread as any correction) where the inner layer
  /// came up to it or through it.
  const std::vector<LayerCover>* layers = nullptr;
};

struct CollisionReport {
  std::size_t checked = 0;         // finite vertices tested
  std::size_t inside_before = 0;   // vertices inside the body before
  std::size_t too_close = 0;       // vertices inside or within the clearance (the constrained ones)
  std::size_t moved = 0;           // vertices whose position changed (constrained + spread)
  double max_displacement = 0.0;
  double mean_displacement = 0.0;  // over the moved vertices
  std::size_t inside_after = 0;
  std::size_t faces_inside_before = 0;  // faces with an interior point inside the body (the body poking through)
  std::size_t faces_inside_after = 0;
  int rounds = 0;
  int inside_rounds = 0;            // of them, rounds over what the others left inside
  std::size_t rechecked = 0;       // vertices checked again by the rounds after the first
  std::size_t layer_covers = 0;    // vertices with another layer over them (CollisionOptions::layers)
  std::size_t layers_crossed_before = 0;  // of them, with that layer closer than it keeps (or through them) before
  std::size_t layers_crossed_after = 0;   // ... and after

  nlohmann::json to_json() const;
};

/// Moves garment vertices out of `body_b` (see above), in place. Vertex
/// adjacency comes from the garment's faces and `l` lines; vertices farther
/// than `smoothing_rings` edges from a constrained vertex never move.
/// Parallel; bit-identical for any thread count. Throws refit::Error when
/// positions and garment differ in vertex count or the clearance is negative.
CollisionReport resolve_penetrations(const Garment& g, Points& positions, const BodySurface& body_b,
                                     const CollisionOptions& options = {});

}  // namespace refit
