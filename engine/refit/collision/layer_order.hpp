#pragma once
// Layers keep their order (beyond the paper): where one layer of a garment lies
// over another in the input (a jacket over trousers, a dress over jeans), the
// collision step keeps it over it. The surface step solves each layer on its own
// and the collision step pushes each off the body on its own, so an inner layer
// came out through the outer one (the shared suit on M_heavier: the trousers
// 0.31 cm through the jacket at the hip, where the input and the warp keep them
// 0.65 cm under it). Lengths in the garment's units.
#include <refit/body/body_surface.hpp>
#include <refit/core/garment.hpp>

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace refit {

/// A vertex of one layer with another layer's surface over it in the input.
struct LayerCover {
  Index inner = 0;                   // the vertex
  std::array<Index, 3> outer{};      // the triangle of the other layer over it
  std::array<double, 3> weight{};    // the point of that triangle over it (barycentric)
  double keep = 0.0;                 // how far over the vertex that point stays, along the triangle's normal
  bool flip = false;                 // the triangle's corner order turns its normal towards the body
};

/// Every vertex of a layer (vertex_layer > 0; 0: loose, no layer) with another
/// layer within `reach` straight out from it (a ray away from body A's closest
/// point): the triangle it meets there, the point, and `keep`, that point's
/// height over the vertex along the triangle's normal (turned outward), up to
/// `gap`. Only vertices with another layer's vertex within a cell of the reach
/// are tried. In vertex order. Empty for a garment of one layer.
std::vector<LayerCover> bind_layer_order(const Garment& g, const std::vector<std::uint32_t>& vertex_layer,
                                         const BodySurface& body_a, double reach, double gap);

/// The outer point's height over the inner vertex on `positions`, along the
/// outer triangle's unit normal turned outward (as bound), and that normal
/// (zero, with height +inf, for a degenerate triangle).
std::pair<double, Vec3> cover_height(const LayerCover& cover, const Points& positions);

}  // namespace refit
