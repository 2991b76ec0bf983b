#pragma once
// Seams: the cut edges of a garment (panels.hpp) chained into seam lines, each
// seen from its two sides, so that the lengths a sewer would join can be
// compared after flattening.
//
// In: the panels and, per cut manifold edge, its two faces and their corners at
// the edge's two vertices. Out: maximal chains of cut edges between the same two
// panels, broken where three or more cut edges meet or where the sides stop
// matching; both sides run in the same direction.
#include <refit/patterns/panels.hpp>

#include <array>
#include <span>
#include <vector>

namespace refit {

struct SeamCorners {
  std::array<Index, 2> face;               // the two faces of the edge
  std::array<std::array<Index, 2>, 2> corner;  // per face, its corners at the edge's vertices x and y
};

/// Chains the cut edges into seams (see above). Edges whose two sides are the
/// same panel edge (a cut that did not open) are left out.
std::vector<Seam> chain_seams(const PanelSet& set, std::span<const SeamCorners> cut_edges);

}  // namespace refit
