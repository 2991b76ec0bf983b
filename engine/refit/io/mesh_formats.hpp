#pragma once
// Body meshes in PLY (ASCII and binary), OFF and STL (ASCII and binary): small
// readers of our own. OpenMesh's readers, used before, looped for ever on a PLY
// header without end_header and allocated without bound for a count in the file
// (a face of 344444444444 corners; found by tests/fuzz). These check every count
// against the bytes left before they allocate, and fail with one line naming the
// file. Polygons are fan-split (a-b-c, a-c-d, ...) as the OBJ reader does; STL
// corners with equal coordinates are merged into one vertex.
#include <refit/body/body_mesh.hpp>

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace refit {

/// Appends the fan triangles a-b-c, a-c-d, ... of one polygon.
template <class Corners>
void fan_split(const Corners& c, std::vector<std::array<Index, 3>>& out) {
  for (std::size_t k = 1; k + 1 < c.size(); ++k) out.push_back({c[0], c[k], c[k + 1]});
}

/// Vertices (x, y, z of element "vertex") and faces (list "vertex_indices" or
/// "vertex_index" of element "face"); other elements and properties are skipped.
BodyMesh parse_ply(std::string_view bytes, const std::string& path);

/// OFF and its variants with colours or normals after each vertex (COFF, NOFF,
/// ...): the first three numbers of a vertex line, the corners of a face line.
BodyMesh parse_off(std::string_view bytes, const std::string& path);

/// Binary when the size is exactly 84 + 50 x the declared triangle count, else
/// ASCII ("solid ... facet ... outer loop, vertex x y z ... endloop").
BodyMesh parse_stl(std::string_view bytes, const std::string& path);

}  // namespace refit
