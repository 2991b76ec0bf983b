#pragma once
// Seam curves of the feature file ("role": "seam") turned into the garment edges
// to cut along: for each curve, the shortest path of face edges that stays close
// to it (Dijkstra; an edge costs its length times 1 + 4 (d / h)^2, d the distance
// of its midpoint from the curve, h the garment's median edge length, and edges
// farther than 4 h are not used).
//
// In: the garment, the seam curves sampled on it (features/feature_curves.hpp),
// and the vertices where a seam may end (the garment's boundary and its other
// cuts). Out: per curve its vertex path. An open curve's ends snap to such a
// vertex within 2 h of them, so that a seam drawn to the hem reaches it. Throws
// refit::Error "FILE: feature 'NAME': ..." when no such path exists.
#include <refit/core/garment.hpp>
#include <refit/features/feature_curves.hpp>

#include <array>
#include <span>
#include <string>
#include <vector>

namespace refit {

struct SeamPath {
  std::string name;
  std::vector<Index> vertices;  // garment vertices along the seam (closed: first not repeated)
  bool closed = false;
  double deviation = 0.0;       // largest distance of a path vertex from the curve
};

/// The edge paths of `seams` on `g` (see above); `file` names the feature file in errors.
std::vector<SeamPath> seam_paths(const Garment& g, std::span<const FeatureCurve> seams, std::span<const char> ends,
                                 const std::string& file);

/// The garment edges (vertex pairs) of the paths.
std::vector<std::array<Index, 2>> seam_path_edges(std::span<const SeamPath> paths);

}  // namespace refit
