#pragma once
// Checks of a resize's input before the work (issue 17). Units and scale: a
// garment in cm on bodies in mm moved 78 cm with exit 0, a body B collapsed to a
// point 81 cm; these are refused from the extents alone, with the likely fix.
// Memory: a run is estimated from its sizes before anything large is allocated.
// Lengths in the garment's units (`units_per_cm` converts the limits, given in
// cm); plain functions of their arguments, safe to call from any thread.
#include <refit/body/body_mesh.hpp>
#include <refit/core/garment.hpp>

#include <string>
#include <vector>

namespace refit {

/// Body A is of human size in the garment's units: 30 to 300 cm along its
/// longest side. For files of people (the command line): a library may bind a
/// doll. Throws refit::Error naming body A's file, with the likely units.
void check_human_size(const BodyMesh& body_a, double units_per_cm);

/// The garment sits on body A: its box's centre within body A's box grown by a
/// fifth of A's height, and at most twice as long. Throws refit::Error naming
/// the garment's file (`units_per_cm` only names the units in the message).
void check_garment_on_body_a(const Garment& garment, const BodyMesh& body_a, double units_per_cm);
/// The same for a garment whose positions' box is [lo, hi] (a garment not in memory).
void check_garment_on_body_a(const Vec3& lo, const Vec3& hi, const std::string& garment_file, const BodyMesh& body_a,
                             double units_per_cm);

/// The vertices of a garment of `vertex_count` that check_garment_over_body_a
/// tests: every k-th, about 4096 of them (all of a smaller garment).
std::vector<Index> depth_check_sample(std::size_t vertex_count);

/// For files of people (the command line; a library may bind a point): the
/// garment, whose positions' box is [lo, hi], is at least a hundredth of body A's
/// height across (eyelashes are 3 cm), and is fitted over body A, not inside it:
/// at most a third of the `sample`d vertices (positions of depth_check_sample's)
/// lie inside body A deeper than a hundredth of its height. The shared garments
/// have none that deep; in inches on bodies in cm, 52-65 % of their vertices
/// are, and the collision step pushed the whole garment out of the body with
/// exit 0 (in m, 0.8 cm across, it was resized as a dot). Throws refit::Error
/// naming the garment's file.
void check_garment_over_body_a(const Points& sample, const Vec3& lo, const Vec3& hi, const std::string& garment_file,
                               const BodyMesh& body_a, double units_per_cm);

/// Body B is from half to twice body A's height and not collapsed (at most half
/// of its triangles, `frames_b`, of zero area). Throws refit::Error naming body B's file.
void check_body_b_scale(const BodyMesh& body_a, const BodyMesh& body_b, const TriangleFrames& frames_b);

}  // namespace refit

namespace refit {

/// Peak memory of a resize in MB, estimated from the garment's vertex count, the
/// surface step's agent count (0 without it) and body A's triangle count, from
/// measured peaks (bench/README.md, "Memory estimate").
double estimated_memory_mb(std::size_t vertices, double agents, std::size_t body_triangles);

}  // namespace refit
