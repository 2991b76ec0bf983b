#pragma once
// Pattern pieces: a garment cut into panels along its seams, the step before
// flattening (issue 16 item 1).
//
// In: a garment with its face attributes (OBJ groups and corner UVs) and the
// garment edges of the seam curves (seam_paths.hpp). Out: panels, each a set of
// faces with its own vertices (a garment vertex on a cut gets one panel vertex
// per side), fan-triangulated and consistently wound, and the seams: the cut
// edges, chained, with their two sides. A face edge is cut where the garment is
// already separate (one face: a boundary), where three or more faces meet, where
// the two faces are in different OBJ groups (`g` / `o`), where their texture
// coordinates differ (a UV seam), or where a seam curve runs. Nothing is
// refused here: a panel that cannot be flattened (closed, with a handle, or
// non-orientable) carries the reason in `problem`.
#include <refit/core/garment.hpp>
#include <refit/io/obj_attributes.hpp>
#include <refit/patterns/flatten.hpp>

#include <array>
#include <span>
#include <string>
#include <vector>

namespace refit {

struct Panel {
  std::string name;                 // the OBJ group's name, "-k" when a group has several panels; "piece-k" without groups
  std::vector<Index> faces;         // garment faces, ascending
  std::vector<Index> vertices;      // panel vertex -> garment vertex
  std::vector<Triangle> triangles;  // fan triangles of the faces, in panel vertices, wound consistently
  std::vector<Index> triangle_face; // the garment face of each triangle
  std::vector<std::vector<Index>> loops;  // boundary loops, in panel vertices, in the triangles' winding
  std::size_t edges = 0;
  int genus = 0;
  std::string problem;              // why it cannot be flattened; empty when it can
};

/// One seam: a chain of cut edges that were sewn in 3D, seen from its two sides.
/// Both paths run in the same direction (path[0][i] and path[1][i] are copies of
/// garment vertex garment_path[i]); panel[0] may equal panel[1] (a slit, a dart).
struct Seam {
  std::array<Index, 2> panel{};
  std::array<std::vector<Index>, 2> path;  // panel vertices along the seam
  std::vector<Index> garment_path;
};

struct PanelSet {
  std::vector<Panel> panels;         // ordered by their first face
  std::vector<Index> face_panel;     // per garment face, its panel
  std::vector<Index> corner_vertex;  // per garment face corner (Garment::faces.indices), its panel vertex
  std::vector<Seam> seams;
  std::size_t uv_seam_edges = 0, group_edges = 0, curve_edges = 0, non_manifold_edges = 0;  // cut edges by reason
};

/// Cuts `g` into panels (see above). `seam_edges` are garment vertex pairs
/// (either order) to cut along besides groups and UV seams. Faces of fewer than
/// three distinct corners still belong to a panel; their triangles are degenerate.
PanelSet cut_panels(const Garment& g, const ObjFaceAttributes& attributes,
                    std::span<const std::array<Index, 2>> seam_edges = {});

}  // namespace refit
