#pragma once
// k-d tree (nanoflann) over a point set, for example the triangle centres of body
// A. The only place nanoflann is used.
#include <refit/core/types.hpp>

#include <memory>
#include <span>
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
  /// The k nearest, closest first (fewer if the tree is smaller). `hint`: k or
  /// more distinct points of the tree thought to be near p (e.g. the previous
  /// query's answer); the k-th nearest of them bounds the search from the start.
  /// The hint only prunes: the answer is the same with or without it.
  void knn(const Vec3& p, std::size_t k, std::vector<Index>& idx, std::vector<double>& dist2,
           std::span<const Vec3> hint = {}) const;
  /// All points with squared distance < r2, closest first.
  void within(const Vec3& p, double r2, std::vector<std::pair<Index, double>>& out) const;
  /// The eq. 2 set of the warp (paper section 3), capped: of the k nearest points,
  /// those with squared distance < scale2 * (the nearest's squared distance),
  /// closest first (the nearest always counts; fewer than k when the radius or the
  /// tree runs out). One search whose pruning radius shrinks with the nearest point
  /// found so far. `hint`: distinct points of the tree thought to be near p (e.g.
  /// the previous query's set); they bound the radius before the search starts
  /// (scale2 times the nearest hint's squared distance, and with k or more hints
  /// the k-th nearest hint's). The hint only prunes: the result is the same
  /// with or without it.
  void nearest_within_scaled(const Vec3& p, std::size_t k, double scale2, std::vector<Index>& idx,
                             std::vector<double>& dist2, std::span<const Vec3> hint = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace refit
