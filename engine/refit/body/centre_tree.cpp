#include <refit/body/centre_tree.hpp>

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace refit {

namespace {
// nanoflann dataset adaptor over a dense copy of the kept points (x, y, z interleaved
// for cache-friendly distance computations inside the tree).
struct Cloud {
  std::vector<double> xyz;
  std::vector<Index> id;  // original row of each kept point
  std::size_t kdtree_get_point_count() const { return id.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return xyz[3 * i + d]; }
  template <class B>
  bool kdtree_get_bbox(B&) const { return false; }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3, Index>;

// nanoflann result set for eq. 2: nanoflann's KNNResultSet (same insertion, so
// the same order among equal distances), but the search radius is also cut to
// scale2 times the nearest distance found so far, and to an optional bound known
// up front. Everything cut lies outside the final set. With scale2 = +inf, the
// k nearest (below the bound).
class ScaledNearestSet {
 public:
  ScaledNearestSet(Index* idx, double* d2, std::size_t capacity, double scale2, double bound2)
      : idx_(idx), d2_(d2), capacity_(capacity), scale2_(scale2), bound2_(bound2) {}
  std::size_t size() const { return count_; }
  bool full() const { return count_ == capacity_; }
  bool addPoint(double dist, Index index) {
    std::size_t i = count_;
    for (; i > 0 && d2_[i - 1] > dist; --i)
      if (i < capacity_) {
        d2_[i] = d2_[i - 1];
        idx_[i] = idx_[i - 1];
      }
    if (i < capacity_) {
      d2_[i] = dist;
      idx_[i] = index;
    }
    if (count_ < capacity_) ++count_;
    return true;
  }
  double worstDist() const {
    double w = bound2_;
    if (count_ > 0 && std::isfinite(scale2_)) w = std::min(w, scale2_ * d2_[0]);  // scale2 +inf: a plain k-nearest set
    if (count_ == capacity_) w = std::min(w, d2_[capacity_ - 1]);
    return w;
  }

 private:
  Index* idx_;
  double* d2_;
  std::size_t capacity_, count_ = 0;
  double scale2_, bound2_;
};

// Where a hinted search may stop looking: k hints as close as the k-th of
// them bound the k-th nearest, and the nearest hint times scale2 bounds the
// scaled set (when scale2 is finite); +inf without enough hints. With a
// relative slack, so a point nanoflann rounds differently from here stays in.
// `scratch` is overwritten.
double hint_bound2(const Vec3& p, std::size_t k, double scale2, std::span<const Vec3> hint, std::vector<double>& scratch) {
  double bound2 = std::numeric_limits<double>::infinity();
  if (hint.empty()) return bound2;
  scratch.resize(hint.size());
  for (std::size_t j = 0; j < hint.size(); ++j) scratch[j] = (p - hint[j]).squaredNorm();
  if (std::isfinite(scale2)) bound2 = scale2 * *std::min_element(scratch.begin(), scratch.end());
  if (hint.size() >= k) {
    std::nth_element(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(k - 1), scratch.end());
    bound2 = std::min(bound2, scratch[k - 1]);
  }
  return bound2 * (1.0 + 1e-9) + 1e-300;
}

}  // namespace

struct PointTree::Impl {
  Cloud cloud;
  std::unique_ptr<Tree> tree;
};

PointTree::PointTree(const Points& points, const std::vector<std::uint8_t>& valid) : impl_(std::make_unique<Impl>()) {
  const Index n = static_cast<Index>(points.rows());
  for (Index i = 0; i < n; ++i) {
    if (!valid.empty() && !valid[i]) continue;
    impl_->cloud.id.push_back(i);
    for (int d = 0; d < 3; ++d) impl_->cloud.xyz.push_back(points(i, d));
  }
  impl_->tree = std::make_unique<Tree>(3, impl_->cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  impl_->tree->buildIndex();
}

PointTree::~PointTree() = default;
PointTree::PointTree(PointTree&&) noexcept = default;
PointTree& PointTree::operator=(PointTree&&) noexcept = default;

std::size_t PointTree::size() const { return impl_->cloud.id.size(); }

std::pair<Index, double> PointTree::nearest(const Vec3& p) const {
  Index idx = 0;
  double d2 = 0.0;
  if (size() == 0) return {0, std::numeric_limits<double>::infinity()};
  nanoflann::KNNResultSet<double, Index> rs(1);
  rs.init(&idx, &d2);
  impl_->tree->findNeighbors(rs, p.data(), nanoflann::SearchParams());
  return {impl_->cloud.id[idx], d2};
}

void PointTree::knn(const Vec3& p, std::size_t k, std::vector<Index>& idx, std::vector<double>& dist2,
                    std::span<const Vec3> hint) const {
  k = std::min(k, size());
  idx.resize(k);
  dist2.resize(k);
  if (k == 0) return;
  // nanoflann's k-nearest set, but with its worst distance capped until it is
  // full: k tree points as close as the hint's k-th bound the k-th nearest, so
  // only farther points (never in the answer) are pruned, and ties among the
  // answer's points go in the same order (ScaledNearestSet's argument).
  const double bound2 = hint_bound2(p, k, std::numeric_limits<double>::infinity(), hint, dist2);
  dist2.resize(k);
  ScaledNearestSet rs(idx.data(), dist2.data(), k, std::numeric_limits<double>::infinity(), bound2);
  impl_->tree->findNeighbors(rs, p.data(), nanoflann::SearchParams());
  idx.resize(rs.size());
  dist2.resize(rs.size());
  for (auto& i : idx) i = impl_->cloud.id[i];
}

void PointTree::nearest_within_scaled(const Vec3& p, std::size_t k, double scale2, std::vector<Index>& idx,
                                      std::vector<double>& dist2, std::span<const Vec3> hint) const {
  k = std::min(k, size());
  idx.resize(k);
  dist2.resize(k);
  if (k == 0) return;
  const double bound2 = hint_bound2(p, k, scale2, hint, dist2);
  dist2.resize(k);
  ScaledNearestSet rs(idx.data(), dist2.data(), k, scale2, bound2);
  impl_->tree->findNeighbors(rs, p.data(), nanoflann::SearchParams());
  std::size_t m = std::min<std::size_t>(1, rs.size());
  while (m < rs.size() && dist2[m] < scale2 * dist2[0]) ++m;
  idx.resize(m);
  dist2.resize(m);
  for (auto& i : idx) i = impl_->cloud.id[i];
}

void PointTree::within(const Vec3& p, double r2, std::vector<std::pair<Index, double>>& out) const {
  out.clear();
  if (size() == 0) return;
  nanoflann::SearchParams params;
  params.sorted = false;  // sorted below, ties by index
  impl_->tree->radiusSearch(p.data(), r2, out, params);
  // nanoflann sorts by distance only; break ties by index so results never depend on tree layout.
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second < b.second : a.first < b.first;
  });
  for (auto& e : out) e.first = impl_->cloud.id[e.first];
  out.erase(std::remove_if(out.begin(), out.end(), [r2](const auto& e) { return !(e.second < r2); }), out.end());
}

}  // namespace refit
