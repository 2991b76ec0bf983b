#include <refit/body/centre_tree.hpp>

#include <nanoflann.hpp>

#include <algorithm>

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

void PointTree::knn(const Vec3& p, std::size_t k, std::vector<Index>& idx, std::vector<double>& dist2) const {
  k = std::min(k, size());
  idx.resize(k);
  dist2.resize(k);
  if (k == 0) return;
  nanoflann::KNNResultSet<double, Index> rs(k);
  rs.init(idx.data(), dist2.data());
  impl_->tree->findNeighbors(rs, p.data(), nanoflann::SearchParams());
  idx.resize(rs.size());
  dist2.resize(rs.size());
  for (auto& i : idx) i = impl_->cloud.id[i];
}

void PointTree::within(const Vec3& p, double r2, std::vector<std::pair<Index, double>>& out) const {
  out.clear();
  if (size() == 0) return;
  nanoflann::SearchParams params;
  params.sorted = true;
  impl_->tree->radiusSearch(p.data(), r2, out, params);
  // nanoflann sorts by distance only; break ties by index so results never depend on tree layout.
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second < b.second : a.first < b.first;
  });
  for (auto& e : out) e.first = impl_->cloud.id[e.first];
  out.erase(std::remove_if(out.begin(), out.end(), [r2](const auto& e) { return !(e.second < r2); }), out.end());
}

}  // namespace refit
