#include <refit/attach/attachment.hpp>

#include <refit/body/body_surface.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace refit {

namespace {

// Best candidate per sample, kept per chunk of work and merged in chunk order so
// the result does not depend on how the work was split.
struct Candidate {
  double d2 = std::numeric_limits<double>::infinity();
  std::array<Index, 3> vertex{};
  std::array<double, 3> weight{};
  Vec3 point = Vec3::Zero();
};


}  // namespace

namespace {

// Closest point of p on a garment element of one (point), two (segment) or three
// (triangle) corners, with barycentric weights of the corners.
Candidate closest_on_element(const Vec3& p, const Points& x, const std::array<Index, 3>& v, int corners) {
  Candidate c;
  const Vec3 a = row3(x, v[0]);
  if (corners == 1) {
    c = {0.0, {v[0], v[0], v[0]}, {1.0, 0.0, 0.0}, a};
  } else if (corners == 2) {
    const Vec3 d = row3(x, v[1]) - a;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    c = {0.0, {v[0], v[1], v[1]}, {1.0 - t, t, 0.0}, a + t * d};
  } else {
    const Vec3 b = row3(x, v[1]), cc = row3(x, v[2]);
    const Vec3 q = closest_point_on_triangle(p, a, b, cc);
    const Vec3 v0 = b - a, v1 = cc - a, v2 = q - a;
    const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
    const double den = d00 * d11 - d01 * d01;
    const double wv = den != 0.0 ? (d11 * d20 - d01 * d21) / den : 0.0;
    const double ww = den != 0.0 ? (d00 * d21 - d01 * d20) / den : 0.0;
    c = {0.0, v, {1.0 - wv - ww, wv, ww}, q};
  }
  c.d2 = (c.point - p).squaredNorm();
  return c;
}

// Every element of the garment once: fan triangles of the faces, segments of the
// `l` polylines, the vertices of `p` elements.
template <class Visit>
void for_each_element(const Garment& g, std::size_t begin, std::size_t end, Visit&& visit) {
  const std::size_t nf = g.faces.rows(), nl = g.lines.rows();
  for (std::size_t e = begin; e < end; ++e) {
    if (e < nf) {
      const auto face = g.faces.row(e);
      for (std::size_t k = 1; k + 1 < face.size(); ++k) visit(std::array<Index, 3>{face[0], face[k], face[k + 1]}, 3);
    } else if (e < nf + nl) {
      const auto line = g.lines.row(e - nf);
      for (std::size_t k = 0; k + 1 < line.size(); ++k) visit(std::array<Index, 3>{line[k], line[k + 1], line[k + 1]}, 2);
    } else {
      for (Index v : g.points.row(e - nf - nl)) visit(std::array<Index, 3>{v, v, v}, 1);
    }
  }
}

}  // namespace

namespace {

float float_below(double v) {
  float f = static_cast<float>(v);
  return double(f) > v ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}
float float_above(double v) {
  float f = static_cast<float>(v);
  return double(f) < v ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

}  // namespace

// The garment's elements in for_each_element order (their id) in an Embree BVH
// (user geometry: triangles, segments and points alike), for exact closest-element
// queries whose cost does not grow with the size of the largest element.
class GarmentLocator::ElementIndex {
 public:
  // The elements of `g` over the positions `x`.
  ElementIndex(const Garment& g, const Points& x) : x_(x) {
    for_each_element(g, 0, g.faces.rows() + g.lines.rows() + g.points.rows(),
                     [&](const std::array<Index, 3>& v, int corners) { elements_.push_back({v, corners}); });
    device_ = rtcNewDevice(nullptr);
    scene_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_LOW);
    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
    // The near radius: twice the median element's bounding box diagonal.
    {
      std::vector<float> size(std::min<std::size_t>(elements_.size(), 4096));
      for (std::size_t i = 0; i < size.size(); ++i) {
        const auto& v = elements_[i * elements_.size() / size.size()].v;
        Vec3 lo = row3(x_, v[0]), hi = lo;
        for (int k = 1; k < 3; ++k) lo = lo.cwiseMin(row3(x_, v[k])), hi = hi.cwiseMax(row3(x_, v[k]));
        size[i] = float((hi - lo).norm());
      }
      std::nth_element(size.begin(), size.begin() + size.size() / 2, size.end());
      near_ = size.empty() ? 0.0f : 0.25f * size[size.size() / 2];
    }
    rtcSetGeometryUserPrimitiveCount(geom, static_cast<unsigned>(elements_.size()));
    rtcSetGeometryUserData(geom, this);
    rtcSetGeometryBoundsFunction(geom, &ElementIndex::bounds, this);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) throw Error("Embree: building the garment's element tree failed");
  }
  ~ElementIndex() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  ElementIndex(const ElementIndex&) = delete;
  ElementIndex& operator=(const ElementIndex&) = delete;

  // The closest point of p on the garment's elements; among equally close
  // elements the first (lowest id), as a scan in element order would find.
  Candidate closest(const Vec3& p) const {
    Query q{this, p, {}};
    RTCPointQuery pq;
    pq.x = static_cast<float>(p.x());
    pq.y = static_cast<float>(p.y());
    pq.z = static_cast<float>(p.z());
    pq.time = 0.0f;
    pq.radius = std::numeric_limits<float>::infinity();
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    // A near radius first (most samples lie on the garment), everything if nothing is that near.
    pq.radius = near_;
    rtcPointQuery(scene_, &pq, &ctx, &ElementIndex::visit, &q);
    const double pad = 1e-6 * p.cwiseAbs().maxCoeff() + 1e-30;
    const double sure = double(near_) * (1.0 - 1e-6) - pad;
    if (!(q.best.d2 <= sure * sure)) {
      // Nothing nearer than the best so far can be missed by a query that reaches it.
      pq.radius = std::isfinite(q.best.d2) ? float_above(std::sqrt(q.best.d2) * (1.0 + 1e-6) + pad)
                                           : std::numeric_limits<float>::infinity();
      rtcInitPointQueryContext(&ctx);
      rtcPointQuery(scene_, &pq, &ctx, &ElementIndex::visit, &q);
    }
    return q.best;
  }

 private:
  struct Element {
    std::array<Index, 3> v;
    int corners;
  };
  struct Query {
    const ElementIndex* index;
    Vec3 p;
    Candidate best;
    std::size_t best_id = std::numeric_limits<std::size_t>::max();
  };

  static void bounds(const RTCBoundsFunctionArguments* args) {
    const auto* self = static_cast<const ElementIndex*>(args->geometryUserPtr);
    const auto& v = self->elements_[args->primID].v;
    Vec3 lo = row3(self->x_, v[0]), hi = lo;
    for (int k = 1; k < 3; ++k) lo = lo.cwiseMin(row3(self->x_, v[k])), hi = hi.cwiseMax(row3(self->x_, v[k]));
    RTCBounds* b = args->bounds_o;
    b->lower_x = float_below(lo.x()), b->lower_y = float_below(lo.y()), b->lower_z = float_below(lo.z());
    b->upper_x = float_above(hi.x()), b->upper_y = float_above(hi.y()), b->upper_z = float_above(hi.z());
  }

  static bool visit(RTCPointQueryFunctionArguments* args) {
    auto* q = static_cast<Query*>(args->userPtr);
    const ElementIndex& self = *q->index;
    const std::size_t id = args->primID;
    // The element's box first: farther than the best so far, the element cannot win.
    const auto& v = self.elements_[id].v;
    const Vec3 a = row3(self.x_, v[0]), b = row3(self.x_, v[1]), cc = row3(self.x_, v[2]);
    const Vec3 lo = a.cwiseMin(b).cwiseMin(cc), hi = a.cwiseMax(b).cwiseMax(cc);
    if ((q->p - q->p.cwiseMax(lo).cwiseMin(hi)).squaredNorm() > q->best.d2) return false;
    const Candidate c = closest_on_element(q->p, self.x_, self.elements_[id].v, self.elements_[id].corners);
    if (!(c.d2 < q->best.d2 || (c.d2 == q->best.d2 && id < q->best_id))) return false;
    q->best = c;
    q->best_id = id;
    // Slightly more than the double distance, plus the query point's rounding to
    // float, so an equally close element is never culled.
    const double pad = 1e-6 * q->p.cwiseAbs().maxCoeff() + 1e-30;
    args->query->radius = float_above(std::sqrt(c.d2) * (1.0 + 1e-6) + pad);
    return true;
  }

  const Points& x_;
  std::vector<Element> elements_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  float near_ = 0.0f;
};

GarmentLocator::GarmentLocator(const Garment& original) {
  if (original.vertex_count() == 0) throw Error("attaching points: the garment has no vertices");
  const bool no_elements = original.faces.rows() + original.lines.rows() + original.points.rows() == 0;
  if (no_elements) {
    std::vector<Index> all(original.vertex_count());
    for (std::size_t v = 0; v < all.size(); ++v) all[v] = Index(v);
    bare_.points.push_row(all);
  }
  index_ = std::make_unique<ElementIndex>(no_elements ? bare_ : original, original.positions);
}

GarmentLocator::~GarmentLocator() = default;

SurfaceAttachment GarmentLocator::attach(const Points& samples) const {
  const std::size_t n = static_cast<std::size_t>(samples.rows());
  SurfaceAttachment at;
  at.vertex.resize(n);
  at.weight.resize(n);
  at.offset.resize(samples.rows(), 3);
  // Work grows with the samples and the garment, not with their product.
  parallel_for(0, n, 256, [&](std::size_t sb, std::size_t se) {
    for (std::size_t s = sb; s < se; ++s) {
      const Vec3 p = samples.row(static_cast<Eigen::Index>(s)).transpose();
      const Candidate best = index_->closest(p);
      at.vertex[s] = best.vertex;
      at.weight[s] = best.weight;
      // Keep the sample's small offset from the surface as it was.
      at.offset.row(static_cast<Eigen::Index>(s)) = (p - best.point).transpose();
    }
  });
  return at;
}

SurfaceAttachment attach_points(const Garment& original, const Points& samples) {
  if (samples.rows() == 0) return {{}, {}, Points(0, 3)};
  return GarmentLocator(original).attach(samples);
}

Vec3 carry_one(const SurfaceAttachment& at, const Points& result, Index i) {
  const auto s = static_cast<std::size_t>(i);
  Vec3 q = row3(at.offset, i);
  for (int k = 0; k < 3; ++k) q += at.weight[s][k] * row3(result, at.vertex[s][k]);
  return q;
}

Points carry(const SurfaceAttachment& at, const Points& result) {
  Points out(at.offset.rows(), 3);
  for (Eigen::Index r = 0; r < out.rows(); ++r) out.row(r) = carry_one(at, result, Index(r)).transpose();
  return out;
}

Points carry_points(const Garment& original, const Points& result, const Points& samples) {
  return carry(attach_points(original, samples), result);
}

}  // namespace refit
