#include <refit/attach/attachment.hpp>

#include <refit/attach/element_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/spatial_order.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace refit {

namespace {

// Every element of the garment once: the fan triangles of the faces, two to
// an element where they share an edge (a quad's two; triangle faces 2j and
// 2j + 1, as a triangulated quad mesh lists them), segments of the `l`
// polylines, the vertices of `p` elements. In this order the triangles come as
// the faces and their fans list them (a scan's order: the first of equally
// close triangles is the one the locator returns).
UninitVector<detail::Element> garment_elements(const Garment& g) {
  const std::size_t nf = g.faces.rows();
  const auto shares_an_edge = [&](std::size_t f) {  // triangle faces f and f + 1
    if (f + 1 >= nf || g.faces.row_size(f) != 3 || g.faces.row_size(f + 1) != 3) return false;
    const auto a = g.faces.row(f), b = g.faces.row(f + 1);
    int common = 0;
    for (Index v : a) common += int(std::count(b.begin(), b.end(), v));
    return common >= 2;
  };
  // Face f's elements start at first[f] (filled in parallel: a million faces).
  const auto elements_of = [&](std::size_t f) -> std::size_t {
    const std::size_t m = g.faces.row_size(f);
    if (m != 3) return (std::max<std::size_t>(m, 2) - 1) / 2;
    if (f % 2 == 1 && shares_an_edge(f - 1)) return 0;  // the second of a pair
    return 1;
  };
  std::vector<std::size_t> first(nf + 1, 0);
  for (std::size_t f = 0; f < nf; ++f) first[f + 1] = first[f] + elements_of(f);
  UninitVector<detail::Element> out(first[nf]);  // every one set below
  parallel_for(0, nf, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) {
      const auto face = g.faces.row(f);
      if (face.size() == 3) {
        if (first[f + 1] == first[f]) continue;  // the second of a pair
        if (f % 2 == 0 && shares_an_edge(f)) {
          const auto next = g.faces.row(f + 1);
          out[first[f]] = {{face[0], face[1], face[2], next[0], next[1], next[2]}, 6};
        } else {
          out[first[f]] = {{face[0], face[1], face[2]}, 3};
        }
        continue;
      }
      // Fan triangles (face[0], face[k], face[k + 1]), k = 1 .. size - 2, two at a time.
      for (std::size_t k = 1, j = first[f]; k + 1 < face.size(); k += 2, ++j)
        out[j] = k + 2 < face.size()
                     ? detail::Element{{face[0], face[k], face[k + 1], face[0], face[k + 1], face[k + 2]}, 6}
                     : detail::Element{{face[0], face[k], face[k + 1]}, 3};
    }
  });
  out.reserve(out.size() + g.lines.indices.size() + g.points.indices.size());
  for (std::size_t l = 0; l < g.lines.rows(); ++l) {
    const auto line = g.lines.row(l);
    for (std::size_t k = 0; k + 1 < line.size(); ++k) out.push_back({{line[k], line[k + 1], line[k + 1]}, 2});
  }
  for (Index v : g.points.indices) out.push_back({{v, v, v}, 1});
  return out;
}

}  // namespace

// The garment's elements in a tree (element_tree.hpp), for exact closest-element
// queries whose cost does not grow with the size of the largest element.
class GarmentLocator::ElementIndex : public detail::ElementTree {
 public:
  using ElementTree::ElementTree;
};

GarmentLocator::GarmentLocator(const Garment& original) {
  if (original.vertex_count() == 0) throw Error("attaching points: the garment has no vertices");
  const bool no_elements = original.faces.rows() + original.lines.rows() + original.points.rows() == 0;
  if (no_elements) {
    std::vector<Index> all(original.vertex_count());
    for (std::size_t v = 0; v < all.size(); ++v) all[v] = Index(v);
    bare_.points.push_row(all);
  }
  index_ = std::make_unique<ElementIndex>(garment_elements(no_elements ? bare_ : original), original.positions);
}

GarmentLocator::~GarmentLocator() = default;

SurfaceAttachment GarmentLocator::attach(const Points& samples) const {
  const std::size_t n = static_cast<std::size_t>(samples.rows());
  SurfaceAttachment at;
  at.vertex.resize(n);
  at.weight.resize(n);
  at.offset.resize(samples.rows(), 3);
  // Work grows with the samples and the garment, not with their product. The
  // samples go in space-filling-curve order: consecutive queries walk the same
  // branches of the tree.
  const UninitVector<Index> order = spatial_order(samples);
  parallel_for(0, n, 256, [&](std::size_t sb, std::size_t se) {
    std::size_t hint = ElementIndex::kNoHint;  // the previous query's element: a bound to start from
    for (std::size_t k = sb; k < se; ++k) {
      const auto s = static_cast<std::size_t>(order[k]);
      const Vec3 p = samples.row(static_cast<Eigen::Index>(s)).transpose();
      const detail::ElementPoint best = index_->closest(p, hint);
      at.vertex[s] = best.vertex;
      at.weight[s] = best.weight;
      // Keep the sample's small offset from the surface as it was.
      at.offset.row(static_cast<Eigen::Index>(s)) = (p - best.point).transpose();
    }
  });
  return at;
}

SurfaceAttachment attach_points(const Garment& original, const Points& samples) {
  if (samples.rows() == 0) return {{}, {}, Points(0, 3)};
  return GarmentLocator(original).attach(samples);
}

std::vector<double> offset_lengths(const SurfaceAttachment& at) {
  std::vector<double> d(static_cast<std::size_t>(at.offset.rows()));
  for (Eigen::Index i = 0; i < at.offset.rows(); ++i) d[static_cast<std::size_t>(i)] = at.offset.row(i).norm();
  return d;
}

Vec3 carry_one(const SurfaceAttachment& at, const Points& result, Index i) {
  const auto s = static_cast<std::size_t>(i);
  Vec3 q = row3(at.offset, i);
  for (int k = 0; k < 3; ++k) q += at.weight[s][k] * row3(result, at.vertex[s][k]);
  return q;
}

Points carry(const SurfaceAttachment& at, const Points& result) {
  Points out(at.offset.rows(), 3);
  parallel_for(0, std::size_t(out.rows()), 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e; ++r) out.row(Eigen::Index(r)) = carry_one(at, result, Index(r)).transpose();
  });
  return out;
}

Points carry_points(const Garment& original, const Points& result, const Points& samples) {
  return carry(attach_points(original, samples), result);
}

}  // namespace refit
