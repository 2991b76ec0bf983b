#include <refit/attach/element_tree.hpp>

#include <refit/body/body_surface.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/spatial_order.hpp>

#include <xmmintrin.h>

#include <algorithm>
#include <bit>
#include <cmath>

namespace refit::detail {

namespace {

constexpr std::size_t kLeaf = 4;
constexpr float kFloatInf = std::numeric_limits<float>::infinity();

// The float next to f (not NaN) towards -inf (down) or +inf (up): std::nextafter
// without its call (two million boxes and discs are rounded out in the build).
float float_step(float f, bool up) {
  if (f == 0.0f) return up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
  const auto bits = std::bit_cast<std::uint32_t>(f);
  return std::bit_cast<float>((f > 0.0f) == up ? bits + 1 : bits - 1);
}
// v rounded to a float no larger (below) or no smaller (above) than v.
float float_below(double v) {
  const float f = static_cast<float>(v);
  return double(f) > v ? float_step(f, false) : f;
}
float float_above(double v) {
  const float f = static_cast<float>(v);
  return double(f) < v ? float_step(f, true) : f;
}

// A two-triangle element's triangle `sub` (0 or 1); any other element itself.
Element part(const Element& e, int sub) {
  if (e.corners != 6) return e;
  const std::size_t o = sub == 0 ? 0 : 3;
  return Element{{e.v[o], e.v[o + 1], e.v[o + 2]}, 3};
}
int parts(const Element& e) { return e.corners == 6 ? 2 : 1; }
// The entries of e.v in use (a segment's or a point's repeat their last corner to the third).
int used(const Element& e) { return e.corners == 6 ? 6 : 3; }

// The closest point of p on element e (at most 3 corners), and its barycentric
// weights on e's corners (computed for the winner only: the same arithmetic either way).
Vec3 closest_point(const Vec3& p, const Points& x, const Element& e) {
  const Vec3 a = row3(x, e.v[0]);
  if (e.corners == 1) return a;
  if (e.corners == 2) {
    const Vec3 d = row3(x, e.v[1]) - a;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    return a + t * d;
  }
  return closest_point_on_triangle(p, a, row3(x, e.v[1]), row3(x, e.v[2]));
}

ElementPoint with_weights(const Vec3& p, const Points& x, const Element& e, const Vec3& q) {
  ElementPoint c;
  const Vec3 a = row3(x, e.v[0]);
  if (e.corners == 1) {
    c = {0.0, {e.v[0], e.v[0], e.v[0]}, {1.0, 0.0, 0.0}, a};
  } else if (e.corners == 2) {
    const Vec3 d = row3(x, e.v[1]) - a;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
    c = {0.0, {e.v[0], e.v[1], e.v[1]}, {1.0 - t, t, 0.0}, q};
  } else {
    const Vec3 b = row3(x, e.v[1]), cc = row3(x, e.v[2]);
    const Vec3 v0 = b - a, v1 = cc - a, v2 = q - a;
    const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
    const double den = d00 * d11 - d01 * d01;
    const double wv = den != 0.0 ? (d11 * d20 - d01 * d21) / den : 0.0;
    const double ww = den != 0.0 ? (d00 * d21 - d01 * d20) / den : 0.0;
    c = {0.0, {e.v[0], e.v[1], e.v[2]}, {1.0 - wv - ww, wv, ww}, q};
  }
  c.d2 = (c.point - p).squaredNorm();
  return c;
}

}  // namespace

ElementPoint closest_on_element(const Vec3& p, const Points& x, const Element& e) {
  const Element first = part(e, 0);
  ElementPoint best = with_weights(p, x, first, closest_point(p, x, first));
  if (parts(e) == 2) {
    // The second only when closer, or when the first has no distance (a
    // degenerate triangle's NaN, which the tree skips as a scan does).
    const Element second = part(e, 1);
    const ElementPoint c = with_weights(p, x, second, closest_point(p, x, second));
    if (c.d2 < best.d2 || (std::isnan(best.d2) && !std::isnan(c.d2))) best = c;
  }
  return best;
}

void ElementTree::Box::grow(const Box& o) {
  for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], o.lo[k]), hi[k] = std::max(hi[k], o.hi[k]);
}

ElementTree::Box ElementTree::box_of(const Element& e) const {
  Vec3 lo = row3(x_, e.v[0]), hi = lo;
  for (int k = 1; k < used(e); ++k) lo = lo.cwiseMin(row3(x_, e.v[k])), hi = hi.cwiseMax(row3(x_, e.v[k]));
  Box b;
  for (int k = 0; k < 3; ++k) b.lo[k] = float_below(lo[k]), b.hi[k] = float_above(hi[k]);
  return b;
}

ElementTree::Disc ElementTree::disc_of(const Element& e) const {
  std::array<Vec3, 6> corner;
  for (int k = 0; k < used(e); ++k) corner[std::size_t(k)] = row3(x_, e.v[std::size_t(k)]);
  const Vec3 &a = corner[0], &b = corner[1], &c = corner[2];
  Vec3 g = Vec3(0.5 * (a + b)), normal = Vec3::Zero();
  if (e.corners == 3) g = (a + b + c) / 3.0, normal = (b - a).cross(c - a);
  if (e.corners == 6) {
    const Vec3 &d = corner[3], &f = corner[4], &h = corner[5];
    g = (a + b + c + d + f + h) / 6.0;
    const Vec3 n0 = (b - a).cross(c - a), n1 = (f - d).cross(h - d);
    normal = n0.dot(n1) >= 0.0 ? Vec3(n0 + n1) : Vec3(n0 - n1);  // the two sides as one, whichever way each turns
  }
  Vec3 n = Vec3::Zero();
  const double len = normal.norm();
  if (len > 0.0 && std::isfinite(len)) n = normal / len;  // else a ball about g
  Disc d;
  for (int k = 0; k < 3; ++k) d.n[k] = float(n[k]), d.g[k] = float(g[k]);
  // The slab's half thickness and the radius, measured from the float n and g
  // that the bound uses: a nearly collinear triangle's normal is rounding noise,
  // not perpendicular to it, and then the slab is as thick as the triangle.
  const Vec3 nf(d.n[0], d.n[1], d.n[2]), gf(d.g[0], d.g[1], d.g[2]);
  double thick = 0.0, r = 0.0;
  for (int k = 0; k < used(e); ++k) {
    const Vec3& v = corner[std::size_t(k)];
    thick = std::max(thick, std::abs(nf.dot(v - gf)));
    r = std::max(r, (v - gf).norm());
  }
  d.thick = float_above(thick);
  d.r = float_above(r);
  return d;
}

// A point of the element lies within `thick` of the plane (n, g) and within r
// of g along it, so its distance from q is at least sqrt((|h| - thick)^2 + (t - r)^2)
// (h: q's height over the plane, t: its distance from g along the plane, each
// term at least 0; with n = 0, a ball: h = 0 and t = |q - g|). The margin taken
// off covers the float rounding of n's length and of the arithmetic (t loses
// precision right over g, where it does not matter), for points as far as
// `scale` (the largest coordinate of q) from the origin.
float ElementTree::distance2(const Disc& d, const std::array<float, 3>& q, float scale) {
  const float v0 = q[0] - d.g[0], v1 = q[1] - d.g[1], v2 = q[2] - d.g[2];
  const float h = v0 * d.n[0] + v1 * d.n[1] + v2 * d.n[2];
  const float t = std::sqrt(std::max(v0 * v0 + v1 * v1 + v2 * v2 - h * h, 0.0f));
  const float off_plane = std::max(std::abs(h) - d.thick, 0.0f);
  const float in_plane = std::max(t - d.r, 0.0f);
  const float g = std::max({std::abs(d.g[0]), std::abs(d.g[1]), std::abs(d.g[2])});
  const float bound = std::sqrt(off_plane * off_plane + in_plane * in_plane) - 4e-6f * (scale + g + d.r);
  return bound > 0.0f ? bound * bound : 0.0f;
}

ElementTree::ElementTree(std::span<const Element> elements, const Points& x) : x_(x) {
  const std::size_t n = elements.size();
  if (n == 0) return;
  const CurveOrder curve = curve_order(n, [&](std::size_t i) {
    const Element& e = elements[i];
    Vec3 lo = row3(x_, e.v[0]), hi = lo;
    for (int k = 1; k < used(e); ++k) lo = lo.cwiseMin(row3(x_, e.v[k])), hi = hi.cwiseMax(row3(x_, e.v[k]));
    return Vec3(0.5 * (lo + hi));
  });
  elements_.resize(n);
  id_.resize(n);
  disc_.resize(n);
  parallel_for(0, n, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const Index i = curve.order[k];
      elements_[k] = elements[i];
      id_[k] = i;
      disc_[k] = disc_of(elements[i]);
    }
  });
  nodes_.reserve(n / kLeaf / 2 + 1);
  root_ = build(curve.key, 0, n, root_box_, nodes_, 2);
}

ElementTree::Ref ElementTree::build(const UninitVector<std::uint64_t>& key, std::size_t b, std::size_t e, Box& box,
                                    std::vector<Node>& nodes, int parallel_levels) const {
  if (e - b <= kLeaf) {
    box = box_of(elements_[b]);
    for (std::size_t k = b + 1; k < e; ++k) box.grow(box_of(elements_[k]));
    return {std::uint32_t(b), std::uint8_t(e - b)};
  }
  // Split where the highest bit in which the range's keys differ turns to 1
  // (keys all equal: in the middle), then each half again: up to four children.
  const auto split = [&](std::size_t lo, std::size_t hi) {
    if (key[lo] == key[hi - 1]) return lo + (hi - lo) / 2;
    const std::uint64_t bit = std::uint64_t(1) << (63 - std::countl_zero(key[lo] ^ key[hi - 1]));
    return std::size_t(std::partition_point(key.begin() + std::ptrdiff_t(lo), key.begin() + std::ptrdiff_t(hi),
                                            [bit](std::uint64_t k) { return !(k & bit); }) -
                       key.begin());
  };
  std::array<std::pair<std::size_t, std::size_t>, 4> part;
  std::size_t parts = 0;
  const std::size_t mid = split(b, e);
  for (const auto& [lo, hi] : {std::pair{b, mid}, std::pair{mid, e}}) {
    if (hi - lo <= kLeaf) {
      part[parts++] = {lo, hi};
    } else {
      const std::size_t m = split(lo, hi);
      part[parts++] = {lo, m};
      part[parts++] = {m, hi};
    }
  }
  const auto index = static_cast<std::uint32_t>(nodes.size());
  nodes.emplace_back();
  Node node;
  for (int s = 0; s < 4; ++s) {
    for (int k = 0; k < 3; ++k) node.lo[k][s] = kFloatInf, node.hi[k][s] = -kFloatInf;
    node.child[s] = 0;
    node.count[s] = 0xff;
  }
  std::array<Box, 4> child_box;
  std::array<Ref, 4> ref;
  if (parallel_levels > 0 && e - b >= (std::size_t(1) << 16)) {
    std::array<std::vector<Node>, 4> sub;
    parallel_for(0, parts, 1, [&](std::size_t sb, std::size_t se) {
      for (std::size_t s = sb; s < se; ++s)
        ref[s] = build(key, part[s].first, part[s].second, child_box[s], sub[s], parallel_levels - 1);
    });
    for (std::size_t s = 0; s < parts; ++s) {  // renumbered as if built here, depth first
      const auto offset = static_cast<std::uint32_t>(nodes.size());
      for (Node& m : sub[s])
        for (int k = 0; k < 4; ++k)
          if (m.count[k] == 0) m.child[k] += offset;
      if (ref[s].count == 0) ref[s].index += offset;
      nodes.insert(nodes.end(), sub[s].begin(), sub[s].end());
    }
  } else {
    for (std::size_t s = 0; s < parts; ++s)
      ref[s] = build(key, part[s].first, part[s].second, child_box[s], nodes, 0);
  }
  for (std::size_t s = 0; s < parts; ++s) {
    for (int k = 0; k < 3; ++k) node.lo[k][s] = child_box[s].lo[k], node.hi[k][s] = child_box[s].hi[k];
    node.child[s] = ref[s].index;
    node.count[s] = ref[s].count;
    if (s == 0) box = child_box[s];
    else box.grow(child_box[s]);
  }
  nodes[index] = node;
  return {index, 0};
}

ElementPoint ElementTree::closest(const Vec3& p, std::size_t& hint) const {
  ElementPoint best;
  if (elements_.empty() || !p.allFinite()) return best;
  std::uint64_t best_key = std::numeric_limits<std::uint64_t>::max();
  // Culling, in float against p rounded to float: a box or disc farther than
  // the best so far plus what the rounding of p and of float arithmetic can
  // hide. No element as close as the best is ever left out.
  const double slack = 2e-7 * p.cwiseAbs().maxCoeff();
  float limit2 = kFloatInf;
  const auto take = [&](std::size_t k) {
    const Element& e = elements_[k];
    for (int sub = 0; sub < parts(e); ++sub) {
      const Element t = part(e, sub);
      const Vec3 q = closest_point(p, x_, t);
      const double d2 = (q - p).squaredNorm();
      const std::uint64_t key = std::uint64_t(id_[k]) * 2 + std::uint64_t(sub);  // a scan's order of the triangles
      if (!(d2 < best.d2 || (d2 == best.d2 && key < best_key))) continue;
      best = with_weights(p, x_, t, q);
      best_key = key;
      hint = k;
      const double reach = std::sqrt(best.d2) * (1.0 + 1e-9) + slack;
      limit2 = float_above(reach * reach * (1.0 + 1e-6));
    }
  };
  if (hint < elements_.size()) take(hint);

  const std::array<float, 3> pf = {float(p[0]), float(p[1]), float(p[2])};
  const float scale = std::max({std::abs(pf[0]), std::abs(pf[1]), std::abs(pf[2])});
  struct Entry {
    Ref ref;
    float d2;
  };
  std::array<Entry, 256> stack;
  std::size_t top = 0;
  float root_d2 = 0.0f;
  for (int k = 0; k < 3; ++k) {
    const float d = std::max(std::max(root_box_.lo[k] - pf[k], pf[k] - root_box_.hi[k]), 0.0f);
    root_d2 += d * d;
  }
  stack[top++] = {root_, root_d2};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.d2 > limit2) continue;
    if (e.ref.count > 0) {
      for (std::size_t k = e.ref.index; k < std::size_t(e.ref.index) + e.ref.count; ++k)
        if (!(distance2(disc_[k], pf, scale) > limit2)) take(k);
      continue;
    }
    const Node& node = nodes_[e.ref.index];
    // The four children's box distances at once (SSE: x86-64's baseline).
    __m128 acc = _mm_setzero_ps();
    for (int k = 0; k < 3; ++k) {
      const __m128 q = _mm_set1_ps(pf[k]);
      const __m128 d = _mm_max_ps(_mm_max_ps(_mm_sub_ps(_mm_load_ps(node.lo[k].data()), q),
                                             _mm_sub_ps(q, _mm_load_ps(node.hi[k].data()))),
                                  _mm_setzero_ps());
      acc = _mm_add_ps(acc, _mm_mul_ps(d, d));
    }
    alignas(16) std::array<float, 4> d2;
    _mm_store_ps(d2.data(), acc);
    // The children within reach in order of distance, the nearest pushed last (searched first).
    std::array<int, 4> slot;
    int m = 0;
    for (int s = 0; s < 4; ++s) {
      if (!(d2[s] <= limit2) || node.count[s] == 0xff) continue;
      int j = m++;
      for (; j > 0 && d2[slot[j - 1]] < d2[s]; --j) slot[j] = slot[j - 1];
      slot[j] = s;
    }
    for (int j = 0; j < m; ++j) stack[top++] = {{node.child[slot[j]], node.count[slot[j]]}, d2[slot[j]]};
  }
  return best;
}

}  // namespace refit::detail
