#pragma once
// Folds left by the warp, smoothed out before the collision step's pushes
// (issue 13, item 4). The warp blends body triangles' frames; where two body
// parts close together move differently (under the arm: arm and torso) it
// crumples the garment at a scale below body A's triangles. The coarse garments'
// 2 cm faces never show it; the dense 1M dress had 6242 of its 2.1M faces turned
// over in the warp and 3004 in the written garment, the vertices near body B
// keeping their warped positions through the surface step.
#include <refit/core/garment.hpp>

#include <cstdint>
#include <vector>

namespace refit {

struct FoldOptions {
  int rings = 2;       // the smoothed region: the folded faces' corners and this many rings around them (times the round)
  int passes = 10;     // Jacobi passes of the smoothing per round
  int feather = 3;     // rings beyond the region whose move eases its edge (0: the edge held as it is)
  int max_rounds = 5;  // re-detect and smooth again (the region grown around what is left) while folds are left
  int reshape_rounds = 5;  // then faces leaning over 60 degrees take their original shape, turned as around (folds.cpp)
};

struct FoldReport {
  std::size_t folded_before = 0;  // faces folded when the smoothing starts
  std::size_t folded_after = 0;   // ... and when it ends
  std::size_t smoothed = 0;       // vertices moved (smoothed or reshaped)
  int rounds = 0;                 // smoothing rounds run
};

/// What the fold smoothing needs of a garment, made once for any number of bodies.
struct FoldBinding {
  Csr faces_of_vertex;                // vertex_faces(g)
  std::vector<std::uint8_t> agrees;   // per face: faces_agreeing on the original
};

/// Per face: whether its normal lies within 60 degrees of the sum of its
/// corners' vertex normals (the sums of their faces' area-weighted normals) (1)
/// or not (0; also degenerate faces): a face away from a crease. A face that
/// agrees on the original and whose normal points against that sum on a result is
/// folded over against its neighbours. `faces_of_vertex`: vertex_faces(g).
std::vector<std::uint8_t> faces_agreeing(const Garment& g, const Csr& faces_of_vertex, const Points& positions);

FoldBinding bind_folds(const Garment& g);

/// Smooths out the faces folded in `positions` (agreeing on the original, not
/// now): their corners and `rings` rings around them take their neighbours' mean
/// displacement from the original (Jacobi passes: a smooth stretch or turn is
/// kept, a crumple is not), and `feather` rings beyond them their neighbours'
/// mean move (the region's move eased off; the vertices beyond held), pinned
/// vertices excepted (per vertex, or null). A round that leaves no fewer folds
/// is tried again with the region's edge held, then undone, and ends the
/// smoothing (the detector misreads some small details). Then the faces
/// still leaning more than 60 degrees off their corners (slivers of a split
/// mesh, which smoothing cannot even out that finely) take their original shape
/// turned as their neighbourhood turned (folds.cpp). Folds are counted with the
/// slivers turned over against their neighbourhood. `adjacency`:
/// vertex_adjacency(g). The same bits for any thread count.
FoldReport smooth_out_folds(const Garment& g, const FoldBinding& binding, Points& positions, const Csr& adjacency,
                            const std::vector<std::uint8_t>* pinned, const FoldOptions& options = {});

}  // namespace refit
