#include <refit/chunked/chunked_features.hpp>

#include <refit/chunked/chunked_topology.hpp>

#include <refit/core/error.hpp>

#include <algorithm>
#include <limits>

namespace refit {
namespace {

// The faces and lines a plane cuts (their order kept), with only their
// vertices (renumbered in order): slice_garment cuts them as it would cut the
// whole garment.
Garment cut_elements(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan, const FeaturePlane& plane) {
  std::vector<Index> ids;
  Csr faces, lines;
  const auto keep = [&](const ElementBlock& b, std::size_t r, bool line, Csr& out) {
    const std::size_t o = b.rows.offsets[r], k = b.rows.row_size(r);
    bool up = false, down = false, crossing = false;
    for (std::size_t c = 0; c < k; ++c) {
      const bool above = plane.signed_distance(b.corner(o + c)) >= 0.0;
      (above ? up : down) = true;
      if (line && c > 0) crossing = crossing || above != (plane.signed_distance(b.corner(o + c - 1)) >= 0.0);
    }
    if (line ? !crossing : !(up && down)) return;
    out.push_row(b.rows.row(r));
    ids.insert(ids.end(), b.rows.row(r).begin(), b.rows.row(r).end());
  };
  for_each_block(g.faces(), plan.chunk_faces, x, [&](const ElementBlock& b) {
    for (std::size_t f = 0; f < b.rows.rows(); ++f) keep(b, f, false, faces);
  });
  for_each_block(g.lines(), plan.chunk_faces, x, [&](const ElementBlock& b) {
    for (std::size_t l = 0; l < b.rows.rows(); ++l) keep(b, l, true, lines);
  });
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  Garment cut;
  x.gather(ids, cut.positions);
  const auto renumber = [&](Csr& c) {
    for (Index& v : c.indices) v = Index(std::lower_bound(ids.begin(), ids.end(), v) - ids.begin());
  };
  renumber(faces);
  renumber(lines);
  cut.faces = std::move(faces);
  cut.lines = std::move(lines);
  return cut;
}

}  // namespace

FeatureGarment chunked_feature_garment(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan) {
  FeatureGarment fg;
  fg.low = g.low();
  fg.high = g.high();
  fg.plane_range = [&g, &plan](const FeaturePlane& plane) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for_each_chunk(g.positions(), plan.chunk_vertices, [&](std::size_t, const Points& rows) {
      for (Eigen::Index i = 0; i < rows.rows(); ++i) {
        const double d = plane.signed_distance(row3(rows, Index(i)));
        lo = std::min(lo, d);
        hi = std::max(hi, d);
      }
    });
    return std::pair<double, double>(lo, hi);
  };
  fg.slice = [&g, &x, &plan](const FeaturePlane& plane, double tolerance) {
    return slice_garment(cut_elements(g, x, plan, plane), plane, tolerance);
  };
  fg.boundary_loops = [&g, &x, &plan](double tolerance) { return chunked_boundary_loops(g, x, plan, tolerance); };
  return fg;
}

}  // namespace refit
