#pragma once
// Geometric queries on a body surface through Embree 3: closest point, signed
// distance and a robust inside test. Thread-safe for queries after construction.
#include <refit/body/body_mesh.hpp>

#include <array>
#include <memory>
#include <vector>

namespace refit {

struct ClosestPoint {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  // unit face normal of the closest triangle (outward for an outward-oriented body)
  double distance = 0.0;       // unsigned
  Index triangle = 0;
};

/// A closest point and, when one was found, whether the query point is inside.
struct SignedClosestPoint : ClosestPoint {
  bool inside = false;  // decided as inside() does; false (and meaningless) when distance is +inf
  // How far p is known to be outside the body: the distance the query found
  // or the radius it searched in vain, even beyond max_distance (0 when inside
  // or unknown). The open ball of this radius about p holds no body point.
  double clear = 0.0;
};

/// Closest point to p on triangle abc (exact, in double).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// What a body's surface takes from its triangles alone: which faces share each
/// edge, which edges and vertices are manifold, each vertex's neighbours. Bodies
/// B have body A's triangles, so one made for body A serves a whole batch.
struct BodyTopology;
/// `body`'s topology (its triangles must use only its vertices: refit::Error otherwise).
std::shared_ptr<const BodyTopology> body_topology(const BodyMesh& body);

class BodySurface {
 public:
  /// `topology`: one made for a body with the same triangles (another body's
  /// topology() is checked and made anew when they differ); null: made here.
  explicit BodySurface(const BodyMesh& body, std::shared_ptr<const BodyTopology> topology = nullptr);
  ~BodySurface();
  BodySurface(BodySurface&&) noexcept;
  BodySurface& operator=(BodySurface&&) noexcept;

  /// This body's topology, for the surfaces of other bodies with the same triangles.
  std::shared_ptr<const BodyTopology> topology() const;

  ClosestPoint closest(const Vec3& p) const;
  /// Closest point no farther than max_distance; distance = +inf when none.
  ClosestPoint closest_within(const Vec3& p, double max_distance) const;
  /// closest_within(p, max_distance).distance < max_distance, the search ended
  /// at the first triangle that close: a yes needs no closest point (eq. 14's
  /// test of a million garment vertices a body, most of them that close).
  bool closer_than(const Vec3& p, double max_distance) const;
  /// The same, triangle `hint` tried first (a yes from it needs no search: a
  /// neighbour's, in a run of neighbouring points); set to the triangle that said
  /// yes. The answer does not depend on it; kNoHint or out of range: none.
  static constexpr Index kNoHint = ~Index(0);
  bool closer_than(const Vec3& p, double max_distance, Index& hint) const;
  /// closest_within() and, when a point was found, inside() from the same query:
  /// within about 1 cm of the surface the closest feature's pseudonormal decides, so
  /// one point query answers both. Nothing within max_distance: distance = +inf
  /// and `inside` is not decided (prove the point outside or call inside()).
  SignedClosestPoint signed_closest_within(const Vec3& p, double max_distance) const;
  /// inside() and, from the same point query where it can, the closest point:
  /// within max_distance when p is outside (distance = +inf when none), anywhere
  /// when inside. The same answers as inside() then closest() or closest_within().
  SignedClosestPoint closest_and_inside(const Vec3& p, double max_distance) const;
  /// True when p is inside the closed body (ray parity, majority over several directions).
  bool inside(const Vec3& p) const;
  /// inside(p), and how far p is known to be outside (SignedClosestPoint::clear;
  /// the other fields are not set).
  SignedClosestPoint inside_or_clear(const Vec3& p) const;
  /// Builds the inside test's lookup grid now; otherwise the first inside() call
  /// builds it. Call it before a parallel loop of inside() tests: built from
  /// within one, the other threads wait for it and it runs on one thread.
  void prepare_inside_test() const;
  /// Negative inside, positive outside.
  double signed_distance(const Vec3& p) const;
  /// The body's vertices within `radius` of p (the first `within` points,
  /// closest first), and the edges with an end among them (each once, as two
  /// rows of `points`; an end outside the radius follows the vertices): what
  /// can rise through a garment face there.
  struct Near {
    std::vector<Vec3> points;
    std::size_t within = 0;
    std::vector<std::array<std::uint32_t, 2>> edges;
  };
  void near(const Vec3& p, double radius, Near& out) const;
  /// Ray cast: distance along unit dir to the first hit, +inf if none; tri_out gets the triangle.
  double intersect(const Vec3& origin, const Vec3& dir, Index* tri_out = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace refit
