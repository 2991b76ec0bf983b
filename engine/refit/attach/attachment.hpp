#pragma once
// Points bound to a garment's surface: where a curve sample sits on the original
// garment, so that the same material point can be found on any deformed state.
#include <refit/core/garment.hpp>

#include <array>
#include <memory>
#include <vector>

namespace refit {

/// Where points sit on a garment: each point's closest point on the garment's
/// elements (fan-triangulated faces, `l` segments, `p` vertices) as three
/// vertices and barycentric weights, plus its small offset from there.
struct SurfaceAttachment {
  std::vector<std::array<Index, 3>> vertex;
  std::vector<std::array<double, 3>> weight;
  Points offset;
};

/// The original garment's elements in a tree, made once for any number of
/// attach() calls (the binding attaches the mirror images of all vertices and
/// the feature samples). Keeps references to `original`, which must outlive it.
class GarmentLocator {
 public:
  explicit GarmentLocator(const Garment& original);
  ~GarmentLocator();
  GarmentLocator(const GarmentLocator&) = delete;
  GarmentLocator& operator=(const GarmentLocator&) = delete;

  /// Each sample's closest point on the elements (among equally close ones, the
  /// first in file order: faces, then lines, then points).
  SurfaceAttachment attach(const Points& samples) const;

 private:
  class ElementIndex;
  std::unique_ptr<ElementIndex> index_;
  Garment bare_;  // a garment without f, l or p elements attaches to its vertices
};

/// GarmentLocator(original).attach(samples), for a single set of samples.
SurfaceAttachment attach_points(const Garment& original, const Points& samples);

/// The attached points on another state of the garment (same vertex order).
Points carry(const SurfaceAttachment& attachment, const Points& result);

/// Attached point `i` on another state of the garment.
Vec3 carry_one(const SurfaceAttachment& attachment, const Points& result, Index i);

/// Per point, its distance to the garment's surface where it was attached (its offset's length).
std::vector<double> offset_lengths(const SurfaceAttachment& attachment);

/// attach_points then carry: the same material points on the result.
Points carry_points(const Garment& original, const Points& result, const Points& samples);

}  // namespace refit
