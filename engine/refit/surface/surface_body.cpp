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

NearBody SurfaceBinding::near_body(const BodySurface& body_b) const {
  // body_distance(p) < epsilon: inside, or closer than epsilon. Most garment
  // vertices of a fitted garment are, and one query of radius epsilon answers
  // for them (the 1M real dress's surface step: 0.63-0.74 s with body_distance's
  // query of radius epsilon + 6 voxels and the inside test, 0.39-0.46 s so), the
  // query ending at the first triangle that close (closer_than).
  const double epsilon = options_.epsilon;
  body_b.prepare_inside_test();
  return [&body_b, epsilon](const Vec3& p) {
    thread_local Index hint = BodySurface::kNoHint;  // this thread's last yes: mostly a neighbour's
    return body_b.closer_than(p, epsilon, hint) || body_b.inside(p);
  };
}

SurfaceResult SurfaceBinding::apply(const Points& warped_vertices, const Points& feature_targets,
                                    const BodySurface& body_b, const Points* feature_warped,
                                    SurfaceSystem* system) const {
  return apply(warped_vertices, feature_targets, body_distance(body_b), near_body(body_b), feature_warped, system);
}

}  // namespace refit
