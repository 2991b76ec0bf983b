#pragma once
// The closest-element search behind GarmentLocator (attachment.hpp), internal
// to attach/: a bounding volume hierarchy over a garment's elements (triangles,
// segments and points, each as three vertex indices), exact in double.
#include <refit/core/types.hpp>

#include <array>
#include <limits>
#include <span>
#include <vector>

namespace refit::detail {

/// The closest point on one element: squared distance, the element's three
/// vertices and the point's barycentric weights on them.
struct ElementPoint {
  double d2 = std::numeric_limits<double>::infinity();
  std::array<Index, 3> vertex{};
  std::array<double, 3> weight{};
  Vec3 point = Vec3::Zero();
};

/// An element: two triangles (corners 6: (v0, v1, v2) then (v3, v4, v5), such
/// as a quad's two fan triangles or two triangle faces that share an edge), a
/// triangle (3), a segment (2: v[2] == v[1]) or a point (1). Two triangles to an
/// element halve the tree of a fine mesh (its build and its depth); the closest
/// point is still a triangle's, the first of the two when equally close.
struct Element {
  std::array<Index, 6> v;
  int corners;
};

/// Closest point of p on element `e` over the positions `x` (of its first
/// triangle when both of a two-triangle element's are as close).
ElementPoint closest_on_element(const Vec3& p, const Points& x, const Element& e);

/// Elements sorted along a space-filling curve, split where their curve keys
/// first differ (a spatial split, as in Karras' linear BVH), in nodes of four
/// children whose boxes are kept in the parent (one node read tests four
/// boxes) and leaves of a few elements, each with a bound of its own: for a
/// triangle (or two) the disc in its plane that holds it, as thick as the
/// rounding of its normal (or the two triangles' bend) needs (tight for points
/// well off a finely meshed surface, where boxes of tilted triangles are not),
/// else a ball.
/// A query descends nearer children first, so its best distance drops at once
/// and every box or disc farther than that is skipped. Keeps a reference to `x`.
class ElementTree {
 public:
  ElementTree(std::span<const Element> elements, const Points& x);

  static constexpr std::size_t kNoHint = std::numeric_limits<std::size_t>::max();
  /// The closest point of p on the elements; among equally close elements the
  /// one given first, as a scan in element order would find. `hint`: a value a
  /// previous query left there (a nearby query's element, which bounds the
  /// search from the start), or kNoHint; set to this query's element. The
  /// result does not depend on the hint.
  ElementPoint closest(const Vec3& p, std::size_t& hint) const;

 private:
  struct Box {
    std::array<float, 3> lo, hi;
    void grow(const Box& o);
  };
  struct Disc {  // plane normal n (zero: a ball) through centre g; the element within
    std::array<float, 3> n, g;  // `thick` of the plane and within r of g
    float r, thick;
  };
  struct alignas(16) Node {  // four children: boxes by axis and slot, and what they are
    std::array<std::array<float, 4>, 3> lo, hi;
    std::array<std::uint32_t, 4> child;  // inner node index, or first element of a leaf
    std::array<std::uint8_t, 4> count;   // leaf: its element count; inner node: 0; unused slot: 0xff
  };
  struct Ref {
    std::uint32_t index;  // node, or first element
    std::uint8_t count;   // 0: node; else a leaf of that many elements
  };

  Box box_of(const Element& e) const;
  Disc disc_of(const Element& e) const;
  static float distance2(const Disc& d, const std::array<float, 3>& q, float scale);
  // The subtree over sorted elements [b, e), its nodes appended to `nodes` in
  // depth-first order; writes its box. The children of the top `parallel_levels`
  // levels are built at once, each into nodes of its own, then appended in
  // order (the same nodes as one depth-first pass).
  Ref build(const UninitVector<std::uint64_t>& key, std::size_t b, std::size_t e, Box& box, std::vector<Node>& nodes,
            int parallel_levels) const;

  const Points& x_;
  // Filled in parallel (UninitVector: no serial zeroing of 100 MB for 2M elements).
  UninitVector<Element> elements_;  // in curve order
  UninitVector<Index> id_;          // each one's position in the given list
  UninitVector<Disc> disc_;         // parallel to elements_
  std::vector<Node> nodes_;
  Ref root_{0, 0};
  Box root_box_{};
};

}  // namespace refit::detail
