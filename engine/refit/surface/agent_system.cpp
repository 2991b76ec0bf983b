#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/surface/agent_system.hpp>
#include <refit/surface/agents.hpp>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace refit {

namespace {
constexpr std::size_t kRowGrain = 1024;
constexpr double kDegenerateDiag = 1e-4;

// Integer block coordinates of every agent (origin at the agents' bounding box minimum).
std::vector<std::array<std::uint32_t, 3>> block_cells(const Points& x, double width) {
  VoxelGrid grid;
  grid.h = width;
  if (x.rows() > 0) grid.origin = x.colwise().minCoeff().transpose();
  std::vector<std::array<std::uint32_t, 3>> c(static_cast<std::size_t>(x.rows()));
  parallel_for(0, c.size(), kRowGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) c[i] = grid.cell(row3(x, Index(i)));
  });
  return c;
}
inline std::uint8_t parity_colour(const std::array<std::uint32_t, 3>& c) {
  return static_cast<std::uint8_t>((c[0] & 1u) | ((c[1] & 1u) << 1) | ((c[2] & 1u) << 2));
}
// Colour in the top bits, then the block's Morton key: sorting by it groups blocks by colour.
inline std::uint64_t block_key(const std::array<std::uint32_t, 3>& c) {
  return (std::uint64_t(parity_colour(c)) << 60) | VoxelGrid::morton({c[0] >> 1, c[1] >> 1, c[2] >> 1});
}
}  // namespace

AgentRows encode_agents(const Points& x, Csr ring) {
  const std::size_t n = ring.rows();
  AgentRows rows;
  rows.weight.assign(ring.indices.size(), 0.0);
  rows.diag.assign(n, 0.0);
  rows.h = Points::Zero(static_cast<Eigen::Index>(n), 3);
  std::vector<std::uint8_t> degenerate(n, 0);
  parallel_for(0, n, kRowGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      auto r = ring.row(a);
      if (r.empty()) continue;
      const Vec3 p = row3(x, Index(a));
      double* w = rows.weight.data() + ring.offsets[a];
      // Eq. 10: lambda_i = |a_i - a|^-2 / sum_j |a_j - a|^-2.
      double sum_inv = 0.0, mean_d = 0.0;
      for (std::size_t i = 0; i < r.size(); ++i) {
        const double d2 = (row3(x, r[i]) - p).squaredNorm();
        w[i] = 1.0 / d2;
        sum_inv += w[i];
        mean_d += std::sqrt(d2);
      }
      mean_d /= static_cast<double>(r.size());
      Vec3 ac = Vec3::Zero();  // eq. 11
      for (std::size_t i = 0; i < r.size(); ++i) {
        w[i] /= sum_inv;
        ac += w[i] * row3(x, r[i]);
      }
      const Vec3 vc = ac - p;
      const double nc = vc.norm();
      double diag = 0.0;
      for (std::size_t i = 0; i < r.size(); ++i) {
        const Vec3 vi = row3(x, r[i]) - p;
        // theta_i undefined where a_c coincides with a: cos = 0 (DESIGN.md).
        const double c = nc > 1e-12 * mean_d ? vc.dot(vi) / (nc * vi.norm()) : 0.0;
        w[i] *= 1.0 - std::clamp(c, -1.0, 1.0);
        diag += w[i];
      }
      if (diag < kDegenerateDiag) {
        // Neighbours in one narrow cone: eq. 13 barely ties a to them. Fall back to
        // w_i = lambda_i (cos theta_i = 0), still weakly diagonally dominant.
        diag = 0.0;
        for (std::size_t i = 0; i < r.size(); ++i) {
          w[i] = 1.0 / (row3(x, r[i]) - p).squaredNorm() / sum_inv;
          diag += w[i];
        }
        degenerate[a] = 1;
      }
      Vec3 h = diag * p;  // eq. 12 made exact at rest
      for (std::size_t i = 0; i < r.size(); ++i) h -= w[i] * row3(x, r[i]);
      rows.diag[a] = diag;
      rows.h.row(static_cast<Eigen::Index>(a)) = h.transpose();
    }
  });
  rows.degenerate = std::accumulate(degenerate.begin(), degenerate.end(), std::size_t{0});
  rows.ring = std::move(ring);
  return rows;
}

double max_residual(const AgentRows& rows, const Points& x) {
  double worst = 0.0;
  for (std::size_t a = 0; a < rows.size(); ++a) {
    auto r = rows.ring.row(a);
    Vec3 s = rows.diag[a] * row3(x, Index(a)) - row3(rows.h, Index(a));
    for (std::size_t i = 0; i < r.size(); ++i) s -= rows.weight[rows.ring.offsets[a] + i] * row3(x, r[i]);
    worst = std::max(worst, s.cwiseAbs().maxCoeff());
  }
  return worst;
}

Points row_residual(const AgentRows& rows, const Points& h, const std::vector<std::uint8_t>& free, const Points& x) {
  Points r = Points::Zero(x.rows(), 3);
  // Neighbours read from x, y, z interleaved (one cache line, not three: as in
  // gauss_seidel); the sums are the same, in the same order.
  const Eigen::Matrix<double, 3, Eigen::Dynamic> p = x.transpose();
  parallel_for(0, rows.size(), 2048, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      if (!free[a]) continue;
      auto ring = rows.ring.row(a);
      Vec3 s = row3(h, Index(a)) - rows.diag[a] * p.col(Eigen::Index(a));
      for (std::size_t i = 0; i < ring.size(); ++i) s += rows.weight[rows.ring.offsets[a] + i] * p.col(Eigen::Index(ring[i]));
      r.row(Eigen::Index(a)) = s.transpose();
    }
  });
  return r;
}

double longest_edge(const Points& x, const Csr& ring) {
  double worst = 0.0;
  for (std::size_t a = 0; a < ring.rows(); ++a)
    for (Index b : ring.row(a)) worst = std::max(worst, (row3(x, b) - row3(x, Index(a))).norm());
  return worst;
}

std::vector<Index> make_block_order(const Points& x, const std::vector<std::uint64_t>& morton, double width) {
  const std::size_t n = static_cast<std::size_t>(x.rows());
  const auto cells = block_cells(x, width);
  struct Key {
    std::uint64_t block, agent;
    Index id;
    bool operator<(const Key& o) const {
      return block != o.block ? block < o.block : (agent != o.agent ? agent < o.agent : id < o.id);
    }
  };
  std::vector<Key> keys(n);
  for (std::size_t i = 0; i < n; ++i) keys[i] = Key{block_key(cells[i]), morton.empty() ? 0 : morton[i], Index(i)};
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<Index> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = keys[i].id;
  return order;
}

BlockSchedule make_schedule(const Points& x, const Csr& ring, double width) {
  const std::size_t n = static_cast<std::size_t>(x.rows());
  BlockSchedule s;
  s.block_width = width;
  const auto cells = block_cells(x, width);
  // Blocks are runs of equal block key in storage order; a block split in two runs
  // is just two blocks (edges between them then go sequential: still correct).
  s.block_of.resize(n);
  std::vector<std::uint64_t> run_key;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t k = block_key(cells[i]);
    if (i == 0 || k != run_key.back()) {
      if (i > 0) s.block_offsets.push_back(static_cast<std::uint32_t>(i));
      run_key.push_back(k);
      s.block_colour.push_back(parity_colour(cells[i]));
    }
    s.block_of[i] = static_cast<std::uint32_t>(run_key.size() - 1);
  }
  if (n > 0) s.block_offsets.push_back(static_cast<std::uint32_t>(n));
  for (std::uint8_t c = 0; c < 8; ++c) {
    std::vector<Index> list;
    for (std::size_t b = 0; b < s.blocks(); ++b)
      if (s.block_colour[b] == c) list.push_back(Index(b));
    s.colour_blocks.push_row(list);
  }
  // An edge between two different blocks of one colour would be a data race:
  // both its agents are swept alone, after the colours.
  s.sequential.assign(n, 0);
  for (std::size_t a = 0; a < n; ++a)
    for (Index b : ring.row(a)) {
      const auto ba = s.block_of[a], bb = s.block_of[b];
      if (ba != bb && s.block_colour[ba] == s.block_colour[bb]) s.sequential[a] = s.sequential[b] = 1;
    }
  for (std::size_t a = 0; a < n; ++a)
    if (s.sequential[a]) s.sequential_agents.push_back(Index(a));
  return s;
}

bool BlockSchedule::concurrent(Index a, Index b) const {
  if (sequential[a] || sequential[b]) return false;
  const auto ba = block_of[a], bb = block_of[b];
  return ba != bb && block_colour[ba] == block_colour[bb];
}

namespace {
// Below this many agents a sweep runs on the calling thread (see gauss_seidel).
constexpr std::size_t kParallelSweepAgents = 8192;
}  // namespace

SolveReport gauss_seidel(const AgentRows& rows, const BlockSchedule& s, const std::vector<std::uint8_t>& free,
                         Points& x, const SolveOptions& options) {
  return gauss_seidel(rows, rows.h, s, free, x, options);
}

SolveReport gauss_seidel(const AgentRows& rows, const Points& hvec, const BlockSchedule& s,
                         const std::vector<std::uint8_t>& free, Points& x, const SolveOptions& options) {
  // The sweep works on x, y, z interleaved (3 x n, column-major): one neighbour
  // read is one cache line instead of three.
  Eigen::Matrix<double, 3, Eigen::Dynamic> p = x.transpose();
  const Index* idx = rows.ring.indices.data();
  const Index* off = rows.ring.offsets.data();
  const double* w = rows.weight.data();
  const double omega = options.relaxation;
  auto update = [&](std::size_t a) -> double {
    if (!free[a] || !(rows.diag[a] > 0.0)) return 0.0;
    double sx = hvec(Eigen::Index(a), 0), sy = hvec(Eigen::Index(a), 1), sz = hvec(Eigen::Index(a), 2);
    for (Index k = off[a]; k < off[a + 1]; ++k) {
      const double* q = p.data() + 3 * std::size_t(idx[k]);
      sx += w[k] * q[0];
      sy += w[k] * q[1];
      sz += w[k] * q[2];
    }
    const double inv = 1.0 / rows.diag[a];
    double* q = p.data() + 3 * a;
    const double dx = omega * (sx * inv - q[0]), dy = omega * (sy * inv - q[1]), dz = omega * (sz * inv - q[2]);
    q[0] += dx;
    q[1] += dy;
    q[2] += dz;
    return dx * dx + dy * dy + dz * dz;
  };
  std::vector<double> block_change(s.blocks(), 0.0);
  auto sweep_blocks = [&](const auto& blocks, std::size_t bb, std::size_t be) {
    for (std::size_t k = bb; k < be; ++k) {
      const Index b = blocks[k];
      double change = 0.0;
      for (std::size_t a = s.block_offsets[b]; a < s.block_offsets[b + 1]; ++a)
        if (!s.sequential[a]) change += update(a);
      block_change[b] = change;
    }
  };
  // Blocks of one colour commute, so sweeping them in turn gives the same bits;
  // small systems (the coarse levels of the multigrid cycles: a few hundred
  // agents, dozens of sweeps per cycle) do, since handing 8 colours a sweep to
  // the threads costs more than the sweep itself.
  const bool in_turn = rows.size() < kParallelSweepAgents;
  SolveReport report;
  for (int it = 0; it < options.max_iterations; ++it) {
    for (std::size_t c = 0; c < s.colour_blocks.rows(); ++c) {
      auto blocks = s.colour_blocks.row(c);
      if (in_turn) {
        sweep_blocks(blocks, 0, blocks.size());
      } else {
        parallel_for(0, blocks.size(), 1, [&](std::size_t bb, std::size_t be) { sweep_blocks(blocks, bb, be); });
      }
    }
    double total = 0.0;
    for (double c : block_change) total += c;
    for (Index a : s.sequential_agents) total += update(a);
    report.iterations = it + 1;
    report.final_update = std::sqrt(total);
    // Plain Gauss-Seidel cannot diverge on these weakly diagonally dominant rows;
    // over-relaxation can (the matrix is not symmetric): never hand back NaN.
    if (!std::isfinite(report.final_update))
      throw Error("surface: the Gauss-Seidel sweeps diverged at iteration " + std::to_string(it + 1) +
                  " (over-relaxation factor " + std::to_string(omega) + " is too large for this system)");
    if (report.final_update < options.tolerance) {
      report.converged = true;
      break;
    }
  }
  x = p.transpose();
  return report;
}

}  // namespace refit
