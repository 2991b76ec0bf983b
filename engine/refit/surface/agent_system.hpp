#pragma once
// Paper sections 5.2-5.3: the local shape encoding of every agent (eqs. 10-12),
// the linear system of eq. 13 in row form, and its parallel, deterministic
// Gauss-Seidel solver over spatial blocks coloured by block-coordinate parity.
// The matrix is never assembled: rows are CSR (neighbour, weight) plus a
// diagonal and the compensation vector h.
#include <refit/core/types.hpp>

#include <cstdint>
#include <vector>

namespace refit {

/// Eq. 13 in row form: diag[a] * x_a - sum_i weight[i] * x_ring[i] = h_a, with
/// weight_i = lambda_i (1 - cos theta_i) and diag = sum_i weight_i.
struct AgentRows {
  Csr ring;                     // one-ring of each agent
  std::vector<double> weight;   // parallel to ring.indices
  std::vector<double> diag;     // per agent
  Points h;                     // compensation vectors (eq. 12), per agent
  /// Rows whose eq.-13 diagonal was below 1e-4 (neighbours all in one narrow cone,
  /// or a single neighbour): encoded with weight_i = lambda_i instead, that is
  /// Laplacian coordinates, so the agent still follows its neighbours.
  std::size_t degenerate = 0;

  std::size_t size() const { return diag.size(); }
};

/// Encodes every agent on `positions` (eqs. 10-12): lambda_i ~ |a_i - a|^-2,
/// a_c = sum lambda_i a_i, theta_i the angle at a between a_i - a and a_c - a
/// (cos theta_i = 0 where a_c coincides with a), h exact at these positions.
/// Agents with an empty ring get diag 0 (they cannot be solved; fix them).
AgentRows encode_agents(const Points& positions, Csr ring);

/// Largest |diag*x_a - sum w_i x_i - h_a| over agents (the encoding's residual at `x`).
double max_residual(const AgentRows& rows, const Points& x);

/// The sweep schedule: agents in spatial blocks (edge `block_width`, at least the
/// longest one-ring edge), blocks coloured by the parity of their coordinates (8
/// colours), blocks of a colour swept in parallel and each block in order.
/// Agents are given in their storage order, which `make_block_order` chose.
struct BlockSchedule {
  std::vector<std::uint32_t> block_offsets{0};   // agents of block b: [block_offsets[b], block_offsets[b+1])
  Csr colour_blocks;                             // row c (0..7): the blocks of colour c, ascending
  std::vector<std::uint8_t> block_colour;        // per block
  std::vector<std::uint32_t> block_of;           // per agent
  std::vector<std::uint8_t> sequential;          // per agent: swept after the colours, alone (a one-ring edge crosses same-colour blocks)
  std::vector<Index> sequential_agents;          // those agents, ascending
  double block_width = 0.0;

  std::size_t blocks() const { return block_offsets.size() - 1; }
  /// True when a and b may be updated at the same time (different blocks of one colour, both parallel).
  bool concurrent(Index a, Index b) const;
};

/// Permutation that stores agents block by block: colour, then block (Morton
/// order of block coordinates), then the agents' own `morton` keys, then index.
/// order[k] = the old index of the agent stored at k.
std::vector<Index> make_block_order(const Points& positions, const std::vector<std::uint64_t>& morton,
                                    double block_width);

/// Schedule for agents already stored in make_block_order's order; marks as
/// sequential every agent with a one-ring edge to another block of its colour.
BlockSchedule make_schedule(const Points& positions, const Csr& ring, double block_width);

/// Per agent the row residual h_a + sum_i w_i x_i - diag_a x_a of eq. 13 with the
/// right-hand side `h` (n x 3); zero where free[a] == 0 (for multigrid corrections).
Points row_residual(const AgentRows& rows, const Points& h, const std::vector<std::uint8_t>& free, const Points& x);

/// Longest one-ring edge at `positions`.
double longest_edge(const Points& positions, const Csr& ring);

struct SolveOptions {
  int max_iterations = 500;
  double tolerance = 1e-5;  // on the L2 norm of one iteration's update over all free agents
  double relaxation = 1.0;  // successive over-relaxation factor (1 = plain Gauss-Seidel)
};
struct SolveReport {
  int iterations = 0;
  double final_update = 0.0;
  bool converged = false;
  double reduction = 0.0;  // multigrid: residual-norm factor of the last V-cycle, or the mean per BiCGSTAB iteration
};

/// Gauss-Seidel on eq. 13 from x (n x 3, updated in place); agents with free[a] == 0
/// keep their x. Deterministic: bit-identical for any thread count. Throws
/// refit::Error when the update norm stops being finite (only over-relaxation,
/// relaxation > 1, can make the sweeps diverge).
SolveReport gauss_seidel(const AgentRows& rows, const BlockSchedule& schedule, const std::vector<std::uint8_t>& free,
                         Points& x, const SolveOptions& options);
/// The same with the compensation vectors `h` (n x 3) in place of rows.h (for
/// example rows.h turned with each agent's local rotation).
SolveReport gauss_seidel(const AgentRows& rows, const Points& h, const BlockSchedule& schedule,
                         const std::vector<std::uint8_t>& free, Points& x, const SolveOptions& options);

}  // namespace refit
