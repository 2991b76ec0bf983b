#pragma once
// Distance between two polylines for the feature tests.
#include <refit/features/bspline.hpp>

#include <algorithm>

namespace refit::test {

/// Symmetric Hausdorff distance between the samples of two polylines (each
/// sample to the other polyline).
inline double hausdorff(const Points& a, bool ca, const Points& b, bool cb) {
  double h = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) h = std::max(h, nearest_on_polyline(b, cb, row3(a, static_cast<Index>(i))).distance);
  for (Eigen::Index i = 0; i < b.rows(); ++i) h = std::max(h, nearest_on_polyline(a, ca, row3(b, static_cast<Index>(i))).distance);
  return h;
}

}  // namespace refit::test
