#include <refit/body/body_surface.hpp>
#include <refit/surface/surface.hpp>

#include <algorithm>

namespace refit {

// Own translation unit: callers of the std::function overload do not need Embree.
std::function<double(const Vec3&)> SurfaceBinding::body_distance(const BodySurface& body_b) const {
  // Only "closer than epsilon" matters, and (for apply's vertex test) a lower bound
  // a little beyond it: the bounded query stops early far from the body, and
  // "farther than the bound" is reported as the bound itself. Inside is negative.
  const double bound = options_.epsilon + 2.0 * options_.reach_voxels * h_;
  body_b.prepare_inside_test();  // apply's first distances come from a parallel loop
  return [&body_b, bound](const Vec3& p) {
    const double d = std::min(body_b.closest_within(p, bound).distance, bound);
    return body_b.inside(p) ? -d : d;
  };
}

SurfaceResult SurfaceBinding::apply(const Points& warped_vertices, const Points& feature_targets,
                                    const BodySurface& body_b, const Points* feature_warped,
                                    SurfaceSystem* system) const {
  return apply(warped_vertices, feature_targets, body_distance(body_b), feature_warped, system);
}

}  // namespace refit
