#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/warp/warp.hpp>

#include <algorithm>
#include <cmath>

namespace refit {

namespace {
constexpr std::size_t kGrain = 1024;
constexpr std::size_t kFirstQuery = 8;

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
  // Each point's set goes to a fixed-size slot first, so the CSR built after is
  // independent of how TBB split the range.
  std::vector<Index> slots(n * k);
  std::vector<std::uint8_t> counts(n);
  std::vector<std::uint8_t> capped(n);
  parallel_for(0, n, kGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<Index> idx;
    std::vector<double> d2;
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 p = row3(points, static_cast<Index>(i));
      // Near the body the eq. 2 set is small: a cheap query for a few centres
      // usually holds all of it; only when it does not, ask for the cap.
      tree_.knn(p, std::min(k, kFirstQuery), idx, d2);
      // Eq. 2: centres strictly within (1+alpha)|pq| of p; the nearest always counts
      // (a point exactly on a centre has |pq| = 0).
      const double r2 = d2[0] * scale2;
      if (k > kFirstQuery && idx.size() == kFirstQuery && d2.back() < r2) tree_.knn(p, k, idx, d2);
      std::size_t m = 1;
      while (m < idx.size() && d2[m] < r2) ++m;
      std::copy_n(idx.begin(), m, slots.begin() + static_cast<std::ptrdiff_t>(i * k));
      counts[i] = static_cast<std::uint8_t>(m);
      capped[i] = (m == k && idx.size() == k) ? 1 : 0;
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
  parallel_for(0, n, kGrain * 8, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      std::copy_n(slots.begin() + static_cast<std::ptrdiff_t>(i * k), counts[i],
                  b.triangles.indices.begin() + b.triangles.offsets[i]);
  });
  return b;
}

Points WarpBinding::apply(const TriangleFrames& b) const {
  const TriangleFrames& a = *reference;
  if (b.size() != a.size())
    throw Error("warp: target body has " + std::to_string(b.size()) + " triangles, the binding expects " +
                std::to_string(a.size()));
  const std::size_t nt = a.size();
  // Per triangle: M = F_B F_A^T (row-major 3x3), so a point's local coordinates
  // on A re-emitted on B are c_B + M (p - c_A).
  std::vector<double> m(9 * nt);
  parallel_for(0, nt, 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const Eigen::Index r = static_cast<Eigen::Index>(t);
      Eigen::Matrix3d fa, fb;
      fa.col(0) = a.u.row(r).transpose();
      fa.col(1) = a.v.row(r).transpose();
      fa.col(2) = a.w.row(r).transpose();
      fb.col(0) = b.u.row(r).transpose();
      fb.col(1) = b.v.row(r).transpose();
      fb.col(2) = b.w.row(r).transpose();
      const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> mt = fb * fa.transpose();
      std::copy_n(mt.data(), 9, m.begin() + static_cast<std::ptrdiff_t>(9 * t));
    }
  });
  const std::size_t n = size();
  Points out(static_cast<Eigen::Index>(n), 3);
  parallel_for(0, n, kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Vec3 p = row3(points, static_cast<Index>(i));
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
