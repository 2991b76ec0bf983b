#pragma once
// k-d tree (nanoflann) over a point set, for example the triangle centres of body
// A. The only place nanoflann is used.
#include <refit/core/types.hpp>

#include <memory>
#include <vector>

namespace refit {

class PointTree {
 public:
  /// Keeps a copy of the points; rows with valid[i] == 0 are left out (valid may be empty).
  explicit PointTree(const Points& points, const std::vector<std::uint8_t>& valid = {});
  ~PointTree();
  PointTree(PointTree&&) noexcept;
  PointTree& operator=(PointTree&&) noexcept;

  std::size_t size() const;
  /// Index of the nearest point and its squared distance.
  std::pair<Index, double> nearest(const Vec3& p) const;
  /// The k nearest, closest first (fewer if the tree is smaller).
  void knn(const Vec3& p, std::size_t k, std::vector<Index>& idx, std::vector<double>& dist2) const;
  /// All points with squared distance < r2, closest first.
  void within(const Vec3& p, double r2, std::vector<std::pair<Index, double>>& out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace refit
