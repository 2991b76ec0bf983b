#include <refit/core/parallel.hpp>
#include <refit/core/union_find.hpp>
#include <refit/surface/agent_frames.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

namespace refit {

namespace {
constexpr std::size_t kFrameGrain = 1024;

Vec3 any_perpendicular(const Vec3& n) {
  const Vec3 t = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return (t - t.dot(n) * n).normalized();
}
}  // namespace

void order_rings(const Points& x, Csr& ring, std::vector<std::uint8_t>& open) {
  const std::size_t n = ring.rows();
  open.assign(n, 0);
  parallel_for(0, n, kFrameGrain, [&](std::size_t b, std::size_t e) {
    std::vector<std::pair<double, Index>> ang;
    for (std::size_t a = b; a < e; ++a) {
      auto r = ring.row(a);
      if (r.size() < 2) continue;
      const Vec3 p = row3(x, Index(a));
      Vec3 mean = p;
      for (Index q : r) mean += row3(x, q);
      mean /= static_cast<double>(r.size() + 1);
      Eigen::Matrix3d cov = (p - mean) * (p - mean).transpose();
      for (Index q : r) cov += (row3(x, q) - mean) * (row3(x, q) - mean).transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
      eig.computeDirect(cov);
      const Vec3 nrm = eig.eigenvectors().col(0);  // smallest eigenvalue
      const Vec3 u = any_perpendicular(nrm), v = nrm.cross(u);
      ang.clear();
      for (Index q : r) {
        const Vec3 d = row3(x, q) - p;
        ang.emplace_back(std::atan2(d.dot(v), d.dot(u)), q);
      }
      std::sort(ang.begin(), ang.end());
      // Largest gap between angularly consecutive neighbours (wrap-around included).
      std::size_t start = 0;
      double widest = ang.front().first + 2.0 * std::numbers::pi - ang.back().first;
      for (std::size_t i = 1; i < ang.size(); ++i)
        if (ang[i].first - ang[i - 1].first > widest) {
          widest = ang[i].first - ang[i - 1].first;
          start = i;
        }
      if (widest > std::numbers::pi) open[a] = 1;
      Index* out = ring.indices.data() + ring.offsets[a];
      for (std::size_t i = 0; i < ang.size(); ++i) out[i] = ang[(start + i) % ang.size()].second;
    }
  });
}

Points fan_normals(const Points& x, const Csr& ring, const std::vector<std::uint8_t>& open) {
  const std::size_t n = ring.rows();
  Points out = Points::Zero(static_cast<Eigen::Index>(n), 3);
  parallel_for(0, n, kFrameGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      auto r = ring.row(a);
      if (r.size() < 2) continue;
      const Vec3 p = row3(x, Index(a));
      Vec3 s = Vec3::Zero();
      const std::size_t fans = open[a] || r.size() == 2 ? r.size() - 1 : r.size();
      for (std::size_t i = 0; i < fans; ++i)
        s += (row3(x, r[i]) - p).cross(row3(x, r[(i + 1) % r.size()]) - p);
      const double len = s.norm();
      // Relative threshold: a fan of collinear points gives no normal.
      double scale = 0.0;
      for (Index q : r) scale = std::max(scale, (row3(x, q) - p).squaredNorm());
      if (len > 1e-12 * scale) out.row(static_cast<Eigen::Index>(a)) = (s / len).transpose();
    }
  });
  return out;
}

std::vector<std::int8_t> orient_normals(const Points& normals, const Csr& ring) {
  const std::size_t n = ring.rows();
  struct Edge {
    double cost;
    Index a, b;
    bool operator<(const Edge& o) const {
      return cost != o.cost ? cost < o.cost : (a != o.a ? a < o.a : b < o.b);
    }
  };
  std::vector<Edge> edges;
  edges.reserve(ring.indices.size());
  for (std::size_t a = 0; a < n; ++a)
    for (Index b : ring.row(a)) {
      const Index lo = std::min<Index>(Index(a), b), hi = std::max<Index>(Index(a), b);
      edges.push_back({1.0 - std::abs(row3(normals, lo).dot(row3(normals, hi))), lo, hi});
    }
  tbb::parallel_sort(edges.begin(), edges.end());  // total order: deterministic
  // Kruskal: the minimal spanning forest.
  std::vector<Index> parent(n);
  std::iota(parent.begin(), parent.end(), Index{0});
  std::vector<std::vector<Index>> tree(n);
  for (const Edge& e : edges) {
    const Index ra = find_root(parent, e.a), rb = find_root(parent, e.b);
    if (ra == rb) continue;
    parent[std::max(ra, rb)] = std::min(ra, rb);
    tree[e.a].push_back(e.b);
    tree[e.b].push_back(e.a);
  }
  // Propagate from the lowest-numbered agent of each group.
  std::vector<std::int8_t> flip(n, 0);
  std::vector<Index> stack;
  for (std::size_t root = 0; root < n; ++root) {
    if (flip[root]) continue;
    flip[root] = 1;
    stack.push_back(Index(root));
    while (!stack.empty()) {
      const Index a = stack.back();
      stack.pop_back();
      const Vec3 na = flip[a] * row3(normals, a);
      for (Index b : tree[a]) {
        if (flip[b]) continue;
        flip[b] = na.dot(row3(normals, b)) < 0.0 ? -1 : 1;
        stack.push_back(b);
      }
    }
  }
  return flip;
}

AgentFrames agent_frames(const Points& x, const Csr& ring, const std::vector<std::uint8_t>& open,
                         const std::vector<std::int8_t>& flip) {
  const std::size_t n = ring.rows();
  const Points normals = fan_normals(x, ring, open);
  AgentFrames f;
  f.origin = x;
  f.axes.assign(n, Eigen::Matrix3d::Identity());
  f.valid.assign(n, 0);
  parallel_for(0, n, kFrameGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const Vec3 nrm = flip[a] * row3(normals, Index(a));
      if (nrm.squaredNorm() < 0.5) continue;
      const Vec3 p = row3(x, Index(a));
      for (Index q : ring.row(a)) {
        const Vec3 d = row3(x, q) - p;
        const Vec3 t = d - d.dot(nrm) * nrm;
        if (t.norm() <= 1e-9 * d.norm()) continue;
        f.axes[a].col(0) = t.normalized();
        f.axes[a].col(1) = nrm;
        f.axes[a].col(2) = f.axes[a].col(0).cross(nrm);
        f.valid[a] = 1;
        break;
      }
    }
  });
  return f;
}

std::vector<Eigen::Matrix3d> ring_rotations(const Points& from, const Points& to, const Csr& ring) {
  const std::size_t n = ring.rows();
  std::vector<Eigen::Matrix3d> out(n, Eigen::Matrix3d::Identity());
  parallel_for(0, n, kFrameGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      auto r = ring.row(a);
      if (r.size() < 2) continue;
      const Vec3 pf = row3(from, Index(a)), pt = row3(to, Index(a));
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      double scale = 0.0;
      for (Index q : r) {
        const Vec3 df = row3(from, q) - pf, dt = row3(to, q) - pt;
        // Edges weighted by 1/|edge|^2: every direction counts alike (a long edge is no surer).
        const double w = 1.0 / std::max(df.squaredNorm(), 1e-300);
        cov += w * dt * df.transpose();
        scale += w * df.squaredNorm();
      }
      Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Vec3 sv = svd.singularValues();
      if (!(sv[1] > 1e-9 * scale)) continue;  // collinear ring: the rotation about the line is unknown
      Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
      if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) d(2, 2) = -1.0;
      out[a] = svd.matrixU() * d * svd.matrixV().transpose();
    }
  });
  return out;
}

std::vector<Eigen::Matrix3d> group_stretches(const Points& from, const Points& to, const std::vector<Index>& group,
                                             std::size_t min_agents) {
  const std::size_t n = group.size();
  // Sums per group in agent order (deterministic): count, means, then covariances.
  std::vector<std::size_t> count(n, 0);
  std::vector<Vec3> mean_from(n, Vec3::Zero()), mean_to(n, Vec3::Zero());
  for (std::size_t a = 0; a < n; ++a) {
    const Index g = group[a];
    ++count[g];
    mean_from[g] += row3(from, Index(a));
    mean_to[g] += row3(to, Index(a));
  }
  for (std::size_t g = 0; g < n; ++g)
    if (count[g] > 0) mean_from[g] /= double(count[g]), mean_to[g] /= double(count[g]);
  std::vector<Eigen::Matrix3d> cff(n, Eigen::Matrix3d::Zero()), ctf(n, Eigen::Matrix3d::Zero());
  for (std::size_t a = 0; a < n; ++a) {
    const Index g = group[a];
    const Vec3 df = row3(from, Index(a)) - mean_from[g], dt = row3(to, Index(a)) - mean_to[g];
    cff[g] += df * df.transpose();
    ctf[g] += dt * df.transpose();
  }
  std::vector<Eigen::Matrix3d> stretch_of(n, Eigen::Matrix3d::Identity());
  for (std::size_t g = 0; g < n; ++g) {
    if (count[g] < min_agents) continue;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> spread(cff[g]);
    const Vec3 ev = spread.eigenvalues();  // ascending
    if (!(ev[2] > 0.0) || !(ev[0] > 1e-4 * ev[2])) continue;  // a flat piece: its normal's scale is unknown
    const Eigen::Matrix3d A = ctf[g] * cff[g].inverse();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> polar(A.transpose() * A);
    const Vec3 s2 = polar.eigenvalues();
    if (!(s2[0] > 0.0) || !A.allFinite()) continue;
    stretch_of[g] = polar.eigenvectors() * s2.cwiseSqrt().asDiagonal() * polar.eigenvectors().transpose();
  }
  std::vector<Eigen::Matrix3d> out(n);
  for (std::size_t a = 0; a < n; ++a) out[a] = stretch_of[group[a]];
  return out;
}

std::vector<Eigen::Matrix3d> frame_rotations(const AgentFrames& before, const AgentFrames& after) {
  const std::size_t n = before.axes.size();
  std::vector<Eigen::Matrix3d> out(n, Eigen::Matrix3d::Identity());
  for (std::size_t a = 0; a < n; ++a)
    if (before.valid[a] && after.valid[a]) out[a] = after.axes[a] * before.axes[a].transpose();
  return out;
}

Points reconstruct_rotations(const Points& v, const Points& before, const Points& after,
                             const std::vector<Eigen::Matrix3d>& rotation, const Csr& reach,
                             const std::vector<float>& weights, const std::vector<Index>& nearest,
                             const std::vector<std::uint8_t>& keep, const Points* kept) {
  const std::size_t n = static_cast<std::size_t>(v.rows());
  Points out(v.rows(), 3);
  parallel_for(0, n, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Vec3 p = row3(v, Index(i));
      auto r = reach.row(i);
      Vec3 q;
      if (r.empty()) {
        const Index j = nearest[i];
        q = !keep.empty() && keep[j] ? row3(*kept, Index(i)) : Vec3(p + row3(after, j) - row3(before, j));
      } else {
        Vec3 sum = Vec3::Zero();
        double wsum = 0.0;
        for (std::size_t k = 0; k < r.size(); ++k) {
          const Index j = r[k];
          const Vec3 d = p - row3(before, j);
          double w;
          if (weights.empty()) {
            const double len = d.norm();
            w = 1.0 / (1e-8 + len * len * len);  // eq. 4
          } else {
            w = weights[reach.offsets[i] + k];
          }
          sum += w * (!keep.empty() && keep[j] ? row3(*kept, Index(i)) : Vec3(row3(after, j) + rotation[j] * d));
          wsum += w;
        }
        q = sum / wsum;
      }
      out.row(static_cast<Eigen::Index>(i)) = q.transpose();
    }
  });
  return out;
}

}  // namespace refit
