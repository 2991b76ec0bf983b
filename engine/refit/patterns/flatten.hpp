#pragma once
// Flattening one pattern piece: a triangulated disk (with holes or slits) in 3D
// to the plane, as-rigid-as-possible (Liu et al. 2008, "A local/global approach
// to mesh parameterization"; the paper's ref. [30] flattens its pants this way),
// started from the least-squares conformal map (Lévy et al. 2002).
//
// In: 3D positions of the piece's vertices and its triangles (consistently
// oriented; every vertex used). Out: 2D positions in the same units, the map
// orientation-preserving for the triangles' winding. The cotangent Laplacian is
// factorised once (Eigen's sparse LDLT); the conformal start is solved by
// conjugate gradients preconditioned with that factor, every ARAP global step
// is two back-substitutions with it (in parallel), the local step runs over the
// triangles in parallel through core/parallel.hpp, and the iterations are
// Anderson-accelerated (Peng et al. 2018; 4 to 5 times fewer on the shared
// garments). Results do not depend on the thread count. Refuses (refit::Error) fewer than 3 vertices or triangles
// with an index out of range.
#include <refit/core/types.hpp>

#include <array>
#include <span>
#include <vector>

namespace refit {

using Points2 = Eigen::Matrix<double, Eigen::Dynamic, 2>;
using Triangle = std::array<Index, 3>;

struct FlattenOptions {
  // Measured on the shared garments (docs/patterns.md): ARAP ends as well from
  // 15 conjugate-gradient iterations of the conformal start as from 50 (stretch
  // p95 within 0.003 either way; CG converges slowly on the nearly conformal
  // modes that ARAP removes anyway) in a third of the time; stopping at 1e-5
  // gives the stretch of 1e-7 in about half the iterations.
  int max_iterations = 300;      // ARAP local/global iterations, at most
  double tolerance = 1e-5;       // stop when an iteration lowers the energy by less than this fraction
  int conformal_iterations = 15; // conjugate-gradient iterations of the conformal start, at most
  // Weight of the held edges (added to the cotangent weights of their
  // triangles): the pattern holds its sewn edges at lengths that both sides of
  // a seam share (pattern.cpp), 100 keeping them within 0.5 % of them.
  double boundary_weight = 100.0;
  bool arap = true;               // false: the conformal map alone
};

struct Flattening {
  Points2 uv;            // one row per vertex
  int iterations = 0;    // ARAP iterations done
  int conformal_iterations = 0;
  double energy = 0.0;   // ARAP energy at the end (area-weighted squared deviation from a rotation)
  bool converged = false;
  // Wall time of the three parts; factor_ms from the call on (checks, boundary, Laplacian, factorisation).
  double factor_ms = 0, conformal_ms = 0, arap_ms = 0;
};

/// An edge of the piece held at a length in 2D (with FlattenOptions::boundary_weight).
struct HeldEdge {
  Index a = 0, b = 0;
  double length = 0;
};

/// Flattens one piece (see above): plain ARAP, but for the `held` edges;
/// from `start` (one row per vertex) instead of the conformal map when given.
/// Throws refit::Error as above, and for a held edge or a start that does not fit.
Flattening flatten_piece(const Points& xyz, std::span<const Triangle> triangles, const FlattenOptions& options = {},
                         std::span<const HeldEdge> held = {}, const Points2* start = nullptr);

}  // namespace refit
