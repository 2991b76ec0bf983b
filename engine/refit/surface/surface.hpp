#pragma once
// Step 3, surface shape optimisation (paper section 5, read with DESIGN.md):
// the warped garment is deformed again so that it passes through the optimised
// feature curves while keeping its original local shape, on any discrete
// surface (soups, hanging edges, loose points, several layers).
//
// Bind once (SurfaceBinding::bind, on the ORIGINAL garment): samples, agents,
// one-rings, the encoding (eqs. 10-12), blocks and colours, fan order and
// normal orientation, and each vertex's agents within reach. Apply many
// (SurfaceBinding::apply, per body B): the constraints (eqs. 14-15), the
// Gauss-Seidel solve of eq. 13 and the reconstruction (eq. 4 blending).
//
// Units: the garment's (SurfaceOptions' epsilon, voxel and clearance too; the
// pipeline converts them from cm). Threads: the binding is read-only after
// bind and apply() is const; the solve runs in parallel inside, with
// bit-identical results for any thread count.
#include <refit/attach/attachment.hpp>
#include <refit/core/garment.hpp>
#include <refit/surface/agent_frames.hpp>
#include <refit/surface/agent_system.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/coarse_levels.hpp>
#include <refit/surface/feature_snap.hpp>

#include <functional>
#include <memory>
#include <span>

namespace refit {

class BodySurface;

struct SurfaceOptions {
  double voxel = 0.0;              // voxel size h in garment units; 0 = auto from the surface size and agent_budget
  std::size_t agent_budget = 20000;  // target agent count for the auto voxel size
  std::size_t max_agents = 1000000;  // an explicit voxel size that needs more is refused (about 1 GB, minutes; issue 17)
  double epsilon = 1.0;            // an agent closer than this to body B keeps its warped position (eq. 14)
  double near_body_band = 0.3;     // beyond the paper, on a piece with features that mostly hangs off the body
                                   // (near_body_band_share): eq. 14's agents are solved with the rest, held only where
                                   // the solve leaves them more than this farther off body B than the warp puts them
                                   // (the clearance rounds keep them off it), and their vertices are not kept at the
                                   // warp: the surface between the features keeps its shape (issue 13). 0: eq. 14
  double near_body_band_share = 1.0 / 3.0;  // ... on pieces with at most this share of their agents within epsilon
                                   // of body B (a skirt hanging from the hips; a fitted dress keeps eq. 14)
  int max_iterations = 500;        // Gauss-Seidel iterations, at most
  double tolerance = 1e-5;         // stop when an iteration's update has an L2 norm below this
  double relaxation = 1.0;         // over-relaxation factor of the sweeps (1 = the paper's Gauss-Seidel). Measured on the
                                   // 6k dress: 1.5 converges 2.8x faster, 1.6 diverges (eq. 13 is not symmetric): kept at 1
  bool encode_on_warped = false;   // encode eqs. 10-12 on the warped agents instead of the original ones
  double reach_voxels = 3.0;       // a vertex is re-emitted from the agents within reach_voxels * h
  double ring_radius_voxels = 3.0; // one-ring candidates lie within this many voxels
  double block_voxels = 8.0;       // solver blocks are at least this many voxels wide (and wider than any one-ring edge)
  std::size_t max_reach_agents = 8;   // a vertex blends its nearest agents (at most this many, within reach)
  bool keep_near_vertices = true;  // garment vertices closer than epsilon to body B keep their warped positions too
  int feature_zone_rings = 1;      // beyond the paper: within this many one-ring steps of a feature agent, and on the
                                   // faces a feature sample sits on, the feature wins over eq. 14: agents there are not
                                   // held at their warped positions, vertices are not kept, and the garment is snapped
                                   // through the optimised curves. 0 = the paper's rule (eq. 14 everywhere but on the
                                   // feature agents), under which a feature running within epsilon of the body (the side
                                   // seams of a tight dress) mostly stays as warped. The clearance rounds and the
                                   // collision step still keep the zone off the body. At most 16
  double zone_edge_blend = 0.3;    // beyond the paper: where the feature zone meets eq. 14's vertices, a vertex within
                                   // epsilon of body B takes its warped position by the share of its blend weights on
                                   // agents outside the zone, eased (smoothstep) from 0 at a share of 0.5 minus this to
                                   // 1 at 0.5 plus this. The zone's reconstruction stands a few mm off the warp, and
                                   // all or nothing (by the nearest agent) made that a cliff one edge wide on a fine
                                   // mesh (the 1M dress's side profiles: a jagged ridge). 0: all or nothing; at most 0.5
  double feature_bend_radius = 16.0;  // beyond the paper: within about this distance of a feature (one-ring steps of
                                   // the voxel size h; garment units, the pipeline passes cm) the surface is solved again
                                   // in least squares over eq. 13's rows and the feature agents' own, so it leaves a
                                   // held curve with the curve's slope instead of a crease (feature_bend.hpp); 0: off
  int feature_slide_rings = 6;     // beyond the paper: near a feature, eq. 14 keeps agents no farther from body B
                                   // instead of in place. The agents it would hold within this many one-ring steps of a
                                   // feature agent are solved with the rest, held no farther off body B than the warp
                                   // puts them (the clearance rounds keep them off it), and keep a share of that
                                   // solution that fades (smoothstep) from the feature to 0 at this many steps; their
                                   // vertices take the warp by the rest. A feature curve whose optimised shape stands
                                   // a few mm off the warp beside the body (the dense dress's side profiles at the
                                   // hips) then slopes into the held surface over these rings instead of one: a raised
                                   // strip with crumpled edges before. 0: eq. 14 as before; at most 64
  bool snap_to_features = true;    // with a feature zone: correct the vertices near the features so that the written
                                   // garment passes through the optimised curves (see feature_snap.hpp)
  double snap_radius = 2.0;         // the correction reaches the vertices within this many voxels (h) of each feature
                                   // sample, weighted (1 - d^2/r^2)^2 (feature_snap.hpp); 0: through the
                                   // reconstruction's blend weights (which can miss a sample's own corners)
  double snap_regularisation = 1e-4;  // Tikhonov weight of that correction, relative to its normal equations' diagonal
  int snap_passes = 4;             // the correction repeated on what is left (each pass removes most of the rest where
                                   // the samples do not conflict; the regularisation keeps one pass from overshooting)
  double snap_remainder_share = 0.5;  // the passes after the first reach this share of snap_radius only (at least the
                                   // corners of each sample's face): spread over the whole radius, what the first
                                   // leaves alternates from sample to sample (diamonds on a fine mesh); 1: every pass alike
  bool keep_clear_of_body = true;  // free agents the solve leaves closer than `clearance` to body B (or inside) are held
                                   // at that clearance and the system is solved again (see apply; false: the paper)
  double clearance = 0.4;          // garment units (the pipeline passes twice its collision clearance, so vertices
                                   // blended between held agents stay out of the collision step's reach)
  int clearance_rounds = 4;        // such re-solves, at most
  int coarse_levels = 4;           // coarse-to-fine start: agent subsets with voxels 2, 4, ... times larger (see apply)
  std::size_t coarse_min_agents = 50;    // no coarser level below this many agents
  int coarse_start_sweeps = 50;    // with multigrid: Gauss-Seidel sweeps per level of the coarse-to-fine start, at most
                                   // (without: max_iterations, as the paper's sweeps need the start)
  bool multigrid = true;           // V-cycles with Galerkin coarse operators after the coarse-to-fine start (false: plain sweeps)
  int multigrid_sweeps = 2;        // Gauss-Seidel sweeps before and after each coarse correction
  int coarsest_sweeps = 50;        // sweeps of the coarsest correction
  double multigrid_overcorrection = 1.5;  // aggregation's usual factor on each coarse correction (measured on the 40k
                                          // demo dress: 164 fine sweeps to the 1e-5 update with 1.0, 82 with 1.5)
  bool krylov = true;              // with multigrid: BiCGSTAB preconditioned by one V-cycle instead of bare V-cycles, whose
                                   // residual reduction per cycle degrades with the agent count (0.80 at 10k agents, 0.97
                                   // at 95k: bench/README.md); false: bare V-cycles
  int krylov_cycle_sweeps = 1;     // Gauss-Seidel sweeps before and after the coarse correction inside that V-cycle
  double tolerance_rms = 0.0;      // > 0: stop when an iteration's update has an RMS over the free agents below this,
                                   // instead of `tolerance` on its L2 norm (which asks sqrt(n) times more of each agent
                                   // as the agent count n grows); 0 = the paper's L2 rule
  bool layers = true;              // beyond the paper: one agent per voxel and layer, rings and blends within a layer
                                   // (see garment_layers; false: the paper's one agent per voxel for the whole garment)
  double layer_min_area = 8.0;     // a piece is a layer from this face area on, in voxel areas (h^2)
  double layer_join = 0.1;         // pieces whose face boundaries come this close (in voxels) are one layer
  // Beyond the paper (each documented where it is used; false gives the paper's way):
  bool follow_body_scale = true;   // scale the local shape encoding by each piece's stretch from the original to the
                                   // warp (group_stretches): the garment follows the body's change of size and
                                   // proportions; false: the paper's absolute size
  bool rotate_encoding = false;    // turn each h (eq. 12) with the agent's ring rotation from the original to the warp (measured worse: see apply)
  bool fit_rotations = true;       // frames as least-squares ring rotations instead of fan normal + one-neighbour tangent
  bool smooth_blend = true;        // vertex blend with a smooth compact kernel bound on the original instead of eq. 4
  int smooth_passes = 5;           // passes of one-ring averaging of the free agents' displacements after the solve
                                   // (0 = the paper's solution as is; see apply)
  bool emit_from_original = true;  // re-emit each vertex from its ORIGINAL offsets to the agents (original -> optimised
                                   // rotations) instead of its warped ones: the warp's creases finer than h go away
};

/// About how many agents binding `g` with `options` makes (the automatic voxel
/// size aims at its budget; an explicit one: face area / h^2 + line length / h,
/// times 1.5). Throws refit::Error naming the voxel size and the garment's extent
/// when an explicit voxel size needs more than max_agents (bind() does too).
double estimated_agent_count(const Garment& g, const SurfaceOptions& options);

struct SurfaceTimings {
  double sample = 0, agents = 0, one_ring = 0, encode = 0;  // bind (encode: at apply when encode_on_warped)
  double solve = 0, reconstruct = 0;                          // apply
};

struct SurfaceStats {
  std::size_t agents = 0, garment_agents = 0, feature_agents = 0, samples = 0;
  std::uint32_t layers = 0;  // layers of the garment (0 without layers; see SurfaceOptions::layers)
  double voxel = 0.0;
  bool voxel_was_auto = false;
  double ring_degree_mean = 0.0;
  std::size_t ring_degree_max = 0;
  std::size_t degenerate_rows = 0;   // rows encoded with the Laplacian fall-back (see AgentRows)
  std::size_t blocks = 0, sequential_agents = 0;
  double block_width = 0.0;
  std::size_t fixed_body = 0, fixed_feature = 0;
  std::size_t banded = 0;           // agents eq. 14 would hold that near_body_band frees (on hanging pieces with features)
  std::size_t feature_slid = 0;     // agents eq. 14 would hold that feature_slide_rings lets follow the features in part
  std::size_t fixed_band = 0;       // ... of which held at their warped distance to body B plus the band
  std::size_t fixed_clearance = 0;  // agents the solve left closer than the clearance to body B, then held at it
  int clearance_rounds = 0;         // re-solves after adding such agents
  std::size_t feature_bend_agents = 0;  // agents solved again around the features (feature_bend.hpp)
  int feature_bend_rings = 0;           // ... within this many one-ring steps of a feature agent
  int feature_bend_rounds = 0;          // ... in this many least-squares solves (one more per clearance round)
  std::size_t anchored = 0, anchored_groups = 0;  // agents (and their groups) with no fixed agent
  std::size_t anchored_followed = 0;  // of those, moved with solved agents within reach (the rest stay as warped)
  int iterations = 0;
  double final_update = 0.0;
  bool converged = false;
  std::size_t vertices_without_agent = 0;  // moved with their nearest agent's displacement
  std::size_t vertices_capped = 0;         // vertices whose agents in reach hit max_reach_agents
  std::size_t vertices_kept = 0;           // vertices within epsilon of body B, left at their warped positions
  int levels = 1;                          // solve levels (1 + coarse levels)
  int coarse_iterations = 0;               // Gauss-Seidel iterations spent on the coarse levels
  int krylov_iterations = 0;               // BiCGSTAB iterations (each: 2 V-cycles, 2 products with the fine matrix)
  double reduction = 0.0;                  // last fine solve: residual factor of its last V-cycle, or mean per BiCGSTAB iteration
  double tolerance = 0.0;                  // the L2 update tolerance the fine solve used (from tolerance_rms when set)
  std::size_t feature_zone_agents = 0;     // agents in the features' zone (feature agents included; 0 without a zone)
  double feature_gap_before_snap = 0.0;    // largest distance from a feature sample carried on the output to its target
  double feature_gap = 0.0;                // the same after the snap (both 0 when the snap is off)
  std::size_t vertices_snapped = 0;        // vertices the snap moved
  SurfaceTimings ms;
};

struct SurfaceResult {
  Points positions;                 // every garment vertex
  Points agents;                    // optimised agent positions (storage order)
  std::vector<float> held;          // per vertex: the share of its warped position it keeps near body B (1: kept at the
                                    // warp, which the snap leaves; between: the zone's edge, whose snap moves shrink so)
  SurfaceStats stats;
};

/// The fine system of apply's last solve, for benchmarks and tests: eq. 13's
/// right-hand side, the free agents (after the clearance rounds), and the start
/// (the coarse-to-fine one; fixed and clearance-held agents at their values).
struct SurfaceSystem {
  Points h;
  std::vector<std::uint8_t> free;
  Points start;
};

/// Each vertex's agents within reach and blend weights (bound on the original
/// garment), for all vertices or a chunk of them (rows in the same order).
struct VertexBlends {
  Csr reach;                  // per vertex: its nearest agents within reach (storage slots)
  std::vector<float> weight;  // smooth_blend: normalised blend weights, parallel to reach.indices
  std::vector<Index> nearest; // per vertex: nearest agent (used when its reach is empty)
  std::size_t capped = 0;     // vertices whose agents in reach hit max_reach_agents
  std::size_t without_agent = 0;
};

/// The feature agents whose corrections move each vertex in the snap
/// (feature_snap.hpp), and their weights, for all vertices or a chunk of them.
struct SnapReach {
  Csr reach;                  // per vertex: feature agents (storage slots)
  std::vector<float> weight;  // parallel to reach.indices
};

/// The garment's share of a surface binding, found on the original garment:
/// by SurfaceBinding::bind from a Garment, or chunk by chunk by the chunked
/// mode (refit/chunked), which then binds with SurfaceBinding::bind_agents.
struct SurfaceGarmentPart {
  double voxel = 0.0;
  bool voxel_auto = false;
  VoxelGrid grid;
  std::uint32_t layers = 0;                  // layers of the garment (0 without layers)
  std::vector<std::uint32_t> feature_layer;  // per feature sample: the layer it sits on
  GarmentAgents agents;                      // select_agents(garment, grid, feature_skip(...), layers)
  Points agent_positions;                    // their positions on the original garment
  std::size_t vertex_count = 0;
  SurfaceTimings ms;                         // sample and agents
};

/// The layer of each feature sample: that of the vertex of largest weight of
/// the face it sits on (all 0 without layers or attachment).
std::vector<std::uint32_t> feature_layers(std::size_t samples, const SurfaceAttachment& attachment,
                                          const std::function<std::uint32_t(Index)>& vertex_layer);

/// Voxels (and layers) of the feature samples: their garment agents are dropped.
std::vector<VoxelLayer> feature_skip(const VoxelGrid& grid, const Points& features,
                                     const std::vector<std::uint32_t>& feature_layer);

/// Refuses (refit::Error naming the voxel size and the garment's extent) a voxel
/// size h that would make more than max_agents agents on a garment of this face
/// area, line length and bounding box extent.
void check_agent_count(double area, double length, const Vec3& extent, double h, std::size_t max_agents);

/// Checks surface options; throws refit::Error naming the bad one.
void check_surface_options(const SurfaceOptions& options);

/// The fine solvers of eq. 13 (SurfaceOptions::multigrid and krylov choose apply's).
enum class FineSolver { sweeps, v_cycles, krylov };

/// The voxel size h that SurfaceBinding::bind uses: options.voxel, or when it is
/// 0 the automatic size for the agent budget (at most one agent per vertex).
double surface_voxel(const Garment& g, const SurfaceOptions& options);

/// The garment's layers as bind finds them with voxel size `voxel` (see
/// garment_layers and SurfaceOptions::layers; empty when layers are off).
std::vector<std::uint32_t> surface_layers(const Garment& g, const SurfaceOptions& options, double voxel);

/// Whether a point is within epsilon of body B or inside it (called from several threads).
using NearBody = std::function<bool(const Vec3&)>;

/// Everything that depends only on the original garment and the feature samples.
class SurfaceBinding {
 public:
  /// Binds `original` and the original positions of all feature samples
  /// (concatenated; they become agents, and a garment agent sharing a voxel with
  /// one is dropped). Throws refit::Error on invalid options, non-finite
  /// positions or bad indices. `feature_attachment`: attach_points(original,
  /// feature_samples) when the caller has it already (it is computed otherwise).
  static SurfaceBinding bind(const Garment& original, const Points& feature_samples, const SurfaceOptions& options = {},
                             const SurfaceAttachment* feature_attachment = nullptr);

  /// The binding from the garment's part, without the per-vertex blends
  /// (vertex_blends gives them a chunk at a time): what bind does after its
  /// garment passes. `feature_attachment`: where the samples sit on the garment.
  static SurfaceBinding bind_agents(SurfaceGarmentPart part, const Points& feature_samples,
                                    const SurfaceOptions& options, SurfaceAttachment feature_attachment);

  /// The blends of vertices at `positions` (original garment) of layers `layer` (per row; empty: all 0).
  VertexBlends vertex_blends(const Points& positions, std::span<const std::uint32_t> layer) const;

  /// The snap's reach of vertices at `positions` (original garment) of layers
  /// `layer`: the feature agents of their layer within snap_radius voxels
  /// (empty with snap_radius 0: the snap then goes through the blends).
  SnapReach snap_reach(const Points& positions, std::span<const std::uint32_t> layer) const;

  /// apply's agent part, for apply and the chunked mode: the constraints, the
  /// solve with its clearance rounds, the anchored agents, the smoothing, and
  /// the rotations every vertex is re-emitted from.
  struct AgentSolution {
    Points before;                         // the agents on the warped garment
    Points x;                              // their solution
    std::vector<Eigen::Matrix3d> rotation; // per agent: from the state vertices are re-emitted from to x
    std::vector<std::uint8_t> keep;        // agents whose vertices are handed back as warped (empty: none)
    std::vector<double> body_distance;     // per agent: its distance to body B (eq. 14)
    std::vector<std::uint8_t> banded;      // per agent: near body B but solved within the band (empty: none)
    std::vector<float> slide;              // per agent: the share of its solution kept near a feature (feature_slide_rings;
                                           // 0: held by eq. 14 or not near body B; empty: none)
    SurfaceStats stats;
  };
  AgentSolution solve_agents(Points before, const Points& feature_targets,
                             const std::function<double(const Vec3&)>& distance_to_body_b, SurfaceSystem* system) const;
  /// apply's re-emission of vertices (all, or a chunk: `original` and `warped`
  /// their rows, `blends` theirs), with eq. 14 for those touching body B
  /// (`carries_feature`: per row, a corner of a face a feature sample sits on;
  /// empty without a zone). Sets `held` (per row, as SurfaceResult::held) and adds to the stats.
  Points emit_vertices(const AgentSolution& solution, const Points& original, const Points& warped,
                       const VertexBlends& blends, std::span<const std::uint8_t> carries_feature,
                       const NearBody& near_body_b, std::vector<float>& held, SurfaceStats& stats) const;
  /// The signed distance to body B that apply(..., body_b, ...) uses (bounded a little beyond epsilon).
  std::function<double(const Vec3&)> body_distance(const BodySurface& body_b) const;
  /// Whether a point is within epsilon of body B or inside it: body_distance's
  /// value under epsilon, from a query of radius epsilon (eq. 14 for vertices).
  NearBody near_body(const BodySurface& body_b) const;
  /// Whether the snap to the features runs (snap_to_features, feature_snap.hpp).
  bool snaps() const;
  /// The share of the snap's radius pass `pass` reaches (snap_remainder_share after
  /// the first pass with the snap's own reach; 1 otherwise), for apply and the chunked mode.
  double snap_share(int pass) const {
    return options_.snap_radius > 0.0 && pass > 0 ? options_.snap_remainder_share : 1.0;
  }
  const std::vector<std::int32_t>& feature_of() const { return feature_of_; }
  const SurfaceAttachment& feature_attachment() const { return feature_attachment_; }

  /// With coarse levels, the free agents start from the solution on the next
  /// coarser agent subset (voxel 2h), interpolated: Gauss-Seidel removes smooth
  /// errors slowly (iterations grow with the squared agent count across the
  /// garment), so a coarse start saves most of them. The fixed point (eq. 13
  /// with eqs. 14-15) is the same. With rotate_encoding, each h is turned by the
  /// rotation that best carries the agent's original ring onto its warped ring.
  ///
  /// Deforms the warped garment so that feature agents reach `feature_targets`
  /// (same rows as the bound feature samples, eq. 15), agents closer than epsilon to
  /// body B keep their warped positions (eq. 14; `distance_to_body_b` is the signed
  /// distance, negative inside, and is called from several threads; it may stop
  /// counting a little beyond epsilon), the rest solve eq. 13, and every vertex is re-emitted
  /// from the agents' frames (eq. 4). `feature_warped` gives the feature samples'
  /// warped positions (their "before" frames); when null, each sample moves with its
  /// nearest garment vertex. Throws refit::Error on size mismatches or non-finite input.
  /// `system`, when given, receives the fine system of the last solve.
  SurfaceResult apply(const Points& warped_vertices, const Points& feature_targets,
                      const std::function<double(const Vec3&)>& distance_to_body_b,
                      const Points* feature_warped = nullptr, SurfaceSystem* system = nullptr) const;
  /// The same with body B's Embree closest-point query.
  SurfaceResult apply(const Points& warped_vertices, const Points& feature_targets, const BodySurface& body_b,
                      const Points* feature_warped = nullptr, SurfaceSystem* system = nullptr) const;

  /// The last step of apply on its own: moves `positions` (every vertex) so the
  /// feature samples reach `feature_targets` (feature_snap.hpp), leaving the
  /// `held` share of each vertex (SurfaceResult::held) where it is. Zero report
  /// without a zone. `passes`: at most this many corrections (0: SurfaceOptions::snap_passes).
  FeatureSnapReport snap(Points& positions, const Points& feature_targets, const std::vector<float>& held,
                         int passes = 0) const;

  /// Eq. 13 on the fine agents (rows() encoding) with right-hand side h, from x
  /// (updated in place; agents with free[a] == 0 keep their x), by `solver` with
  /// this binding's coarse levels and multigrid options. `krylov_iterations`,
  /// when given, is increased by the BiCGSTAB iterations made.
  SolveReport solve(const Points& h, const std::vector<std::uint8_t>& free, Points& x, const SolveOptions& options,
                    FineSolver solver, int* krylov_iterations = nullptr) const;

  // Bound data, for tests, benchmarks and tools. Agents are in storage (block) order.
  const SurfaceOptions& options() const { return options_; }
  double voxel() const { return h_; }
  std::size_t agent_count() const { return static_cast<std::size_t>(original_agents_.rows()); }
  /// Per garment vertex, its layer (garment_layers; empty without layers).
  const std::vector<std::uint32_t>& vertex_layers() const { return vertex_layer_; }
  std::size_t feature_count() const { return static_cast<std::size_t>(feature_slot_.size()); }
  const Points& original_agents() const { return original_agents_; }
  /// Storage slot of feature sample k.
  const std::vector<Index>& feature_slots() const { return feature_slot_; }
  const AgentRows& rows() const { return rows_; }  // encoded on the original (empty ring/weights when encode_on_warped)
  const Csr& ring() const { return ring_; }
  const BlockSchedule& schedule() const { return schedule_; }
  /// Agent positions on a state of the garment (rows = garment vertices); feature
  /// agents from `feature_positions` (or moved with their nearest vertex when null).
  Points agent_positions(const Points& vertices, const Points* feature_positions) const;
  /// The garment vertices agent_positions reads (sorted): the garment agents' and the feature samples' attachment.
  std::vector<Index> agent_vertices() const;
  /// agent_positions with the position of vertex ids[k] in row k of `vertices` (ids: agent_vertices()).
  Points agent_positions(const Points& vertices, const std::vector<Index>& ids, const Points* feature_positions) const;
  /// Bind-time statistics (agents, voxel, rings, blocks, bind timings).
  const SurfaceStats& bind_stats() const { return stats_; }

 private:
  template <class Vertex>
  Points agent_positions_of(const Vertex& vertex, const Points* feature_positions) const;
  // V-cycles on the fine system with aggregation coarse levels (solver.cpp).
  SolveReport solve_multigrid(const AgentRows& rows, const Points& h, const std::vector<std::uint8_t>& free, Points& x,
                              const SolveOptions& solve, bool krylov, int* krylov_iterations) const;
  // The steps of apply (surface.cpp, reconstruct.cpp; each documented where defined).
  Points coarse_to_fine_start(const Points& before, const Points& target_of, const std::vector<std::uint8_t>& fixed,
                              const std::vector<Eigen::Matrix3d>& turn, const std::vector<std::uint8_t>& fine_free,
                              const SolveOptions& solve, int& coarse_iterations) const;
  std::size_t follow_anchored(const Points& before, const std::vector<std::uint8_t>& fixed,
                              const std::vector<std::uint8_t>& fr, Points& x,
                              std::vector<std::uint8_t>& anchored_kept) const;
  void smooth_displacements(const Points& before, const std::vector<std::uint8_t>& fr, Points& x) const;
  std::vector<Eigen::Matrix3d> rotations(const Points& before, const Points& x, const std::vector<Eigen::Matrix3d>& stretch) const;
  std::vector<float> keep_near_vertices(const AgentSolution& solution, const Points& warped,
                                        const VertexBlends& blends, std::span<const std::uint8_t> carries_feature,
                                        const NearBody& near_body_b, Points& positions) const;
  SurfaceResult apply(const Points& warped_vertices, const Points& feature_targets,
                      const std::function<double(const Vec3&)>& distance_to_body_b, const NearBody& near_body_b,
                      const Points* feature_warped, SurfaceSystem* system) const;

  SurfaceOptions options_;
  double h_ = 0.0;
  std::size_t vertex_count_ = 0;
  // Per slot: garment agents as vertex combinations; feature agents have feature_of >= 0.
  std::vector<std::array<Index, 3>> src_vertex_;
  std::vector<std::array<double, 3>> src_weight_;
  std::vector<std::int32_t> feature_of_;
  std::vector<std::uint8_t> near_feature_;     // per agent: in the features' zone (empty without a zone)
  std::vector<std::uint8_t> carries_feature_;  // per vertex: a corner of a face a feature sample sits on (with a zone)
  std::vector<Index> feature_slot_;
  std::vector<std::uint32_t> layer_;      // per agent (storage order): its layer (all 0 without layers)
  SurfaceAttachment feature_attachment_;  // where each feature sample sits on the original garment
  Points original_agents_;
  Csr ring_;                         // angular order (see order_rings)
  std::vector<std::uint8_t> ring_open_;
  std::vector<std::int8_t> flip_;
  AgentRows rows_;
  BlockSchedule schedule_;
  std::vector<Index> group_;         // connected group of each agent (one-ring graph)
  std::size_t groups_ = 0;
  std::vector<std::uint32_t> vertex_layer_;  // per garment vertex: its layer (bind; empty without layers or from bind_agents)
  VertexBlends blends_;              // per garment vertex (bind; empty from bind_agents)
  SnapReach snap_reach_;             // per garment vertex with snap_radius > 0 (bind; empty from bind_agents)
  Points original_vertices_;         // emit_from_original: the garment's original positions
  std::vector<CoarseLevel> levels_;  // coarser levels, finest first (coarse_levels.hpp)
  SurfaceStats stats_;
};

}  // namespace refit
