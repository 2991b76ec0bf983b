#pragma once
// Coarser agent subsets of the surface step (beyond the paper), for its
// coarse-to-fine start and the multigrid solver: every feature agent, and per
// voxel of a grid 2, 4, ... times coarser the agent nearest the voxel's centre,
// each level with its own one-rings, encoding (eqs. 10-12) and schedule. Levels
// are subsets of the fine agents, so the body distances, feature targets and
// rotations of the fine agents serve them too (no garment resampling).
// Built once at bind; read-only afterwards (safe to share between threads).
#include <refit/core/types.hpp>
#include <refit/surface/agent_system.hpp>

#include <cstdint>
#include <vector>

namespace refit {

struct CoarseLevel {
  std::vector<Index> agent;      // fine storage slot of each agent of the level (level storage order)
  Csr ring;
  AgentRows rows;
  BlockSchedule schedule;
  std::vector<Index> group;      // connected group (one-ring graph of the level)
  Csr up;                        // per agent of the next finer level: the level's agents it interpolates from
  std::vector<float> up_weight;  // parallel to up.indices
};

/// Connected groups of a one-ring graph: group[a] = the lowest agent of a's group.
std::vector<Index> ring_groups(const Csr& ring);

/// One-rings of `natural` (within `radius`, per layer), then the storage order
/// block by block (blocks at least `min_width` wide and wider than the longest
/// one-ring edge, so rings come first). order[k] = the natural index stored at
/// k; ring in storage indices.
struct OrderedAgents {
  std::vector<Index> order;
  Csr ring;
  double width = 0.0;
};
OrderedAgents order_agents(const Points& natural, const std::vector<std::uint64_t>& morton,
                           const std::vector<std::uint32_t>& layer, double radius, double min_width);

/// Up to `max_levels` coarser levels of the fine agents (storage order), finest
/// first, each with voxel h * 2^l, none below `min_agents` agents and none that
/// keeps more than 3/4 of the level below. Ring radius and block width in voxels
/// of each level. feature_of[a] >= 0 marks feature agents (kept on every level).
std::vector<CoarseLevel> build_coarse_levels(const Points& agents, const std::vector<std::uint32_t>& layer,
                                             const std::vector<std::int32_t>& feature_of, double h, int max_levels,
                                             std::size_t min_agents, double ring_radius_voxels, double block_voxels);

}  // namespace refit
