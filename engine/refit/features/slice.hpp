#pragma once
// Cutting a garment by a feature plane (the "slice" feature kind, paper section
// 4.2 and Fig. 3(b)): works on what CAD files hold (faces of any size,
// non-manifold edges, polygon soups with duplicated coincident vertices).
#include <refit/core/garment.hpp>
#include <refit/core/weld.hpp>
#include <refit/features/plane.hpp>

#include <vector>

namespace refit {

/// One chained cut: an ordered polyline, closed when it comes back to its start
/// (then the first point is not repeated).
struct SlicePiece {
  Points points;
  bool closed = false;
};

struct SliceResult {
  std::vector<SlicePiece> pieces;  // from the faces, longest chains first is NOT implied: deterministic order
  Points line_points;              // where `l` hanging edges cross the plane (single points, not chained)
  std::size_t segments = 0;        // face cut segments after welding and removing duplicates
};


/// Cuts the faces of `g` by `plane` and chains the cut segments into polylines.
/// A vertex exactly on the plane counts as being on the normal's side (so every
/// crossing is a proper edge crossing); crossing points are computed from the
/// edge's endpoints in a canonical (coordinate) order, so coincident duplicated
/// vertices give identical points; points closer than `weld_tolerance` (<= 0:
/// 1e-6 of the garment's bounding-box diagonal) are merged, so soups and split
/// seams chain through. At a non-manifold junction the chain continues along the
/// straightest segment. Parallel over faces; the result does not depend on the
/// thread count.
SliceResult slice_garment(const Garment& g, const FeaturePlane& plane, double weld_tolerance = 0.0);

}  // namespace refit
