#pragma once
// A human body: a triangle mesh, in the garment's units. Bodies A and B must share their triangle list (same
// connectivity), so triangle i on A corresponds to triangle i on B. A plain value, read from any number of threads.
#include <refit/core/types.hpp>

#include <array>
#include <string>
#include <vector>

namespace refit {

struct BodyMesh {
  Points vertices;                               // n x 3
  std::vector<std::array<Index, 3>> triangles;   // quads and polygons fan-split on load
  std::string name;                              // file stem, for messages and output names
  std::string path;                              // file it came from ("" if generated)
};

/// Throws refit::Error naming the first difference (vertex count, triangle count,
/// or the first triangle whose corners differ) when b does not correspond to a.
void check_same_connectivity(const BodyMesh& a, const BodyMesh& b);

/// Throws refit::Error naming the file when a vertex is NaN/inf, a triangle
/// index is out of range, or the body has no triangles.
void check_body(const BodyMesh& body);

/// Per-triangle centre and orthonormal frame (u along the first edge, w the unit
/// normal, v = w x u), SoA. Degenerate triangles (zero area) get valid = 0 and are
/// never used by the warp.
struct TriangleFrames {
  Points centre, u, v, w;
  std::vector<std::uint8_t> valid;
  std::size_t degenerate = 0;
  std::size_t size() const { return valid.size(); }
};

TriangleFrames compute_frames(const BodyMesh& body);

}  // namespace refit
