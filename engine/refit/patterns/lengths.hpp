#pragma once
// Lengths of polylines in 2D or 3D (rows of points), and of paths and loops
// given by row indices: the pattern's outlines, seams and lines.
#include <refit/core/types.hpp>

#include <vector>

namespace refit {

/// Sum of the distances between consecutive rows (closed: and last to first).
template <class P>
double rows_length(const P& p, bool closed) {
  double len = 0;
  for (Eigen::Index i = 0; i + 1 < p.rows(); ++i) len += (p.row(i + 1) - p.row(i)).norm();
  if (closed && p.rows() > 2) len += (p.row(0) - p.row(p.rows() - 1)).norm();
  return len;
}

/// The same along rows `index[0], index[1], ...` of `p`.
template <class P>
double indexed_length(const P& p, const std::vector<Index>& index, bool closed) {
  double len = 0;
  for (std::size_t i = 0; i + 1 < index.size(); ++i) len += (p.row(index[i + 1]) - p.row(index[i])).norm();
  if (closed && index.size() > 2) len += (p.row(index.front()) - p.row(index.back())).norm();
  return len;
}

}  // namespace refit
