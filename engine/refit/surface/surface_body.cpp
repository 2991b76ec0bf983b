#include <refit/body/body_surface.hpp>
#include <refit/surface/surface.hpp>

namespace refit {

// Own translation unit: callers of the std::function overload do not need Embree.
SurfaceResult SurfaceBinding::apply(const Points& warped_vertices, const Points& feature_targets,
                                    const BodySurface& body_b, const Points* feature_warped) const {
  const double eps = options_.epsilon;
  // Only "closer than epsilon" matters: the bounded query stops early far from the body.
  return apply(warped_vertices, feature_targets,
               [&body_b, eps](const Vec3& p) { return body_b.closest_within(p, eps).distance; }, feature_warped);
}

}  // namespace refit
