#pragma once
// Topology of a garment as a CAD file gives it (non-manifold, soups, hanging
// edges, loose points): edge incidence, boundary loops and connected components.
#include <refit/core/garment.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace refit {

struct TopologyStats {
  std::size_t vertices = 0, faces = 0, lines = 0, points = 0;
  std::size_t unreferenced_vertices = 0;  // used by no face, line or point
  std::size_t edges = 0;                  // distinct undirected face edges
  std::size_t boundary_edges = 0;         // face edges with exactly one face
  std::size_t non_manifold_edges = 0;     // face edges with three or more faces
  std::size_t boundary_loops = 0;
  std::size_t components = 0;             // over faces, lines and points together (unreferenced vertices excluded)
};

TopologyStats topology_stats(const Garment& g);

/// Boundary loops of the faces (edges used by exactly one face), each an ordered
/// closed vertex cycle (first vertex not repeated). Deterministic order.
std::vector<std::vector<Index>> boundary_loops(const Garment& g);

/// The loops boundary_loops walks, from the boundary edges `boundary` (each
/// (lo << 32) | hi with lo < hi, ascending) and the direction its face gives
/// each (forward[e]: lo to hi). Needs memory for the boundary only.
std::vector<std::vector<Index>> boundary_loops_of(const std::vector<std::uint64_t>& boundary,
                                                  const std::vector<std::uint8_t>& forward);

/// The ends of the boundary edges (used by exactly one face side) with every
/// vertex v read as id[v] (for example welded vertices; id[v] < vertex count),
/// as ids, ascending, without repeats. Linear in the face corners.
std::vector<Index> boundary_vertices(const Garment& g, const std::vector<Index>& id);

/// Vertex adjacency (CSR, sorted, no duplicates) from faces and `l` lines.
Csr vertex_adjacency(const Garment& g);

/// Per vertex, the faces it is a corner of (CSR, ascending, each face once).
Csr vertex_faces(const Garment& g);

/// The faces with a corner among `vertices`, ascending, each once;
/// `faces_of_vertex`: vertex_faces(g).
std::vector<Index> faces_around(const Csr& faces_of_vertex, std::span<const Index> vertices);

}  // namespace refit
