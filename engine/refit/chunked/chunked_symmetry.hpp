#pragma once
// Symmetry in chunks (issue 14): each vertex's mirror image attached to the
// garment's surface (GarmentBinding's symmetry binding) for a stored garment,
// and the symmetrised garment a chunk at a time.
//
// The mirror images are attached slab by slab of space along the garment's
// longest axis: a slab's queries meet a GarmentLocator of the elements within
// `radius` of the slab, which finds the closest element (the first in file
// order among equally close ones) of every query closer than `radius` to the
// garment; queries farther go to another round with a larger radius, until the
// 95th percentile of the distances is known. Those left (farther than every
// radius tried, never paired) keep an infinite distance.
#include <refit/chunked/chunk_plan.hpp>
#include <refit/chunked/garment_store.hpp>

#include <array>
#include <cstdint>
#include <limits>

namespace refit {

/// A vertex's mirror image on the garment's surface (SurfaceAttachment's row).
struct MirrorRecord {
  std::array<Index, 3> vertex{};
  std::array<double, 3> weight{};
  std::array<double, 3> offset{};
  double distance() const;  // |offset|: the image's distance to the surface (infinite when not found)
};

struct ChunkedMirror {
  RecordFile<MirrorRecord> records;  // per vertex
  double garment_error = 0.0;        // 95th percentile of the distances (check_symmetry's garment error)
  int rounds = 0;
  std::size_t columns = 0;           // tiles of slabs cut across (a dense slab's elements split to a chunk's size)
};

/// The mirror images about x = plane_x of all vertices of `g`, exact within `radius`.
ChunkedMirror chunked_mirror_attach(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan, double plane_x,
                                    double radius);

/// Rows [first, first + s.rows()) of the symmetrised garment: each vertex whose
/// image is within `tolerance` becomes the mean of itself and its image's
/// mirror, carried on `positions` (GarmentBinding::resize's symmetrisation).
Points symmetrised_rows(const RecordFile<MirrorRecord>& mirror, const PointGather& positions, std::size_t first,
                        const Points& s, double plane_x, double tolerance);

/// Rows [first, first + b.rows()) of `b` (rows of `before`) with each vertex's
/// move to `a` (rows of `after`) made, where its image is within `tolerance`,
/// the mean of its own and its image's move, mirrored (GarmentMirror::symmetrise_moves).
Points symmetrised_move_rows(const RecordFile<MirrorRecord>& mirror, const PointGather& before, const PointGather& after,
                             std::size_t first, const Points& b, const Points& a, double tolerance);

}  // namespace refit
