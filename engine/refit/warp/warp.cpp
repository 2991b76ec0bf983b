#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/warp/warp.hpp>

#include <algorithm>
#include <cmath>

namespace refit {

namespace {
constexpr std::size_t kGrain = 1024;

// Eq. 4's weight; |(u, v, w)| = |p - c| because the frame is orthonormal.
inline double blend_weight(const Vec3& d) {
  const double r = d.norm();
  return 1.0 / (1e-8 + r * r * r);
}
}  // namespace

ReferenceBody::ReferenceBody(BodyMesh body, WarpOptions options)
    : body_(std::move(body)),
      options_(options),
      frames_(std::make_shared<const TriangleFrames>(compute_frames(body_))),
      tree_(frames_->centre, frames_->valid) {
  if (options_.max_triangles == 0) throw Error("warp: max_triangles must be at least 1");
  if (!(options_.alpha >= 0.0)) throw Error("warp: alpha must be non-negative");
  if (tree_.size() == 0) throw input_error(body_.path.empty() ? body_.name : body_.path, "body has no non-degenerate triangle");
}

WarpBinding ReferenceBody::bind(const Points& points) const {
  const std::size_t n = static_cast<std::size_t>(points.rows());
  const std::size_t k = options_.max_triangles;
  const double scale2 = (1.0 + options_.alpha) * (1.0 + options_.alpha);
  // Fixed blocks of points, each with its own list: concatenated in block order,
  // the CSR does not depend on how TBB ran them, and memory is what the sets
  // need (not n * k slots).
  const std::size_t blocks = (n + kGrain - 1) / kGrain;
  std::vector<std::vector<Index>> found(blocks);
  std::vector<Index> counts(n);
  std::vector<std::uint8_t> capped(n);
  parallel_for(0, blocks, 1, [&](std::size_t b0, std::size_t b1) {
    std::vector<Index> idx;
    std::vector<double> d2;
    for (std::size_t blk = b0; blk < b1; ++blk) {
      const std::size_t first = blk * kGrain, last = std::min(n, first + kGrain);
      std::vector<Index>& out = found[blk];
      out.reserve((last - first) * std::min<std::size_t>(k, 4));
      // Consecutive points are usually close: the previous point's set bounds this
      // one's search radius before the search starts (only pruning: the set is the
      // same without it).
      std::vector<Vec3> hint;
      for (std::size_t i = first; i < last; ++i) {
        const Vec3 p = row3(points, static_cast<Index>(i));
        // Eq. 2: the (at most k) nearest centres strictly within (1+alpha)|pq| of p;
        // the nearest always counts (a point exactly on a centre has |pq| = 0).
        tree_.nearest_within_scaled(p, k, scale2, idx, d2, hint);
        hint.clear();
        for (Index t : idx) hint.push_back(row3(frames_->centre, t));
        out.insert(out.end(), idx.begin(), idx.end());
        counts[i] = static_cast<Index>(idx.size());
        capped[i] = idx.size() == k ? 1 : 0;
      }
    }
  });
  WarpBinding b;
  b.points = points;
  b.reference = frames_;
  b.triangles.offsets.resize(n + 1);
  b.triangles.offsets[0] = 0;
  for (std::size_t i = 0; i < n; ++i) {
    b.triangles.offsets[i + 1] = b.triangles.offsets[i] + counts[i];
    b.capped += capped[i];
  }
  b.triangles.indices.resize(b.triangles.offsets[n]);
  parallel_for(0, blocks, 8, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t blk = b0; blk < b1; ++blk) {
      std::copy(found[blk].begin(), found[blk].end(), b.triangles.indices.begin() + b.triangles.offsets[blk * kGrain]);
      std::vector<Index>().swap(found[blk]);
    }
  });
  return b;
}

TriangleChange triangle_change(const TriangleFrames& a, const TriangleFrames& b) {
  if (b.size() != a.size())
    throw Error("warp: target body has " + std::to_string(b.size()) + " triangles, the binding expects " +
                std::to_string(a.size()));
  const std::size_t nt = a.size();
  TriangleChange c{&a, &b, std::vector<double>(9 * nt), std::vector<std::uint8_t>(nt)};
  // A vertex whose triangles are all where they were on A keeps its position to
  // the bit (A = B gives the garment back, issue 17), not p + (c - c) + R R^T d.
  parallel_for(0, nt, 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const Eigen::Index r = static_cast<Eigen::Index>(t);
      c.moved[t] = !(a.centre.row(r) == b.centre.row(r) && a.u.row(r) == b.u.row(r) && a.v.row(r) == b.v.row(r) &&
                     a.w.row(r) == b.w.row(r) && a.valid[t] == b.valid[t]);
      Eigen::Matrix3d fa, fb;
      fa.col(0) = a.u.row(r).transpose();
      fa.col(1) = a.v.row(r).transpose();
      fa.col(2) = a.w.row(r).transpose();
      fb.col(0) = b.u.row(r).transpose();
      fb.col(1) = b.v.row(r).transpose();
      fb.col(2) = b.w.row(r).transpose();
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> mt = fb * fa.transpose();
      std::copy_n(mt.data(), 9, c.m.begin() + static_cast<std::ptrdiff_t>(9 * t));
    }
  });
  return c;
}

Points WarpBinding::apply(const TriangleFrames& b) const { return apply(triangle_change(*reference, b)); }

Points WarpBinding::apply(const TriangleChange& change) const {
  if (change.a != reference.get()) throw Error("internal: a warp applied with another body A's change");
  const TriangleFrames& a = *change.a;
  const TriangleFrames& b = *change.b;
  const std::vector<double>& m = change.m;
  const std::vector<std::uint8_t>& moved = change.moved;
  const std::size_t n = size();
  Points out(static_cast<Eigen::Index>(n), 3);
  parallel_for(0, n, kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 p = row3(points, static_cast<Index>(i));
      bool still = true;
      for (Index t : triangles.row(i)) still = still && !moved[t];
      if (still) {
        out.row(static_cast<Eigen::Index>(i)) = p.transpose();
        continue;
      }
      Vec3 acc = Vec3::Zero();
      double wsum = 0.0;
      for (Index t : triangles.row(i)) {
        if (!b.valid[t]) continue;
        const Vec3 d = p - row3(a.centre, t);
        const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> mt(m.data() + 9 * std::size_t(t));
        const double w = blend_weight(d);
        acc += w * (row3(b.centre, t) + mt * d);
        wsum += w;
      }
      Vec3 q;
      if (wsum > 0.0) {
        q = acc / wsum;
      } else {  // every triangle of the set collapsed on B: follow the nearest one's centre
        const Index t = triangles.row(i)[0];
        q = p - row3(a.centre, t) + row3(b.centre, t);
      }
      out.row(static_cast<Eigen::Index>(i)) = q.transpose();
    }
  });
  return out;
}

}  // namespace refit
