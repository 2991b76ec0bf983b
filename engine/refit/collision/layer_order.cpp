// Which layer lies over which in the input (layer_order.hpp).
#include <refit/collision/layer_order.hpp>

#include <refit/body/embree_ray.hpp>
#include <refit/body/embree_scene.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace refit {

namespace {

// Grid cells of the reach, packed 21 bits per axis.
struct Cells {
  Vec3 lo;
  double size;
  std::uint64_t key(const Vec3& p) const {
    std::uint64_t k = 0;
    for (int a = 0; a < 3; ++a) k = (k << 21) | std::uint64_t(std::clamp(std::floor((p[a] - lo[a]) / size), 0.0, 2097151.0));
    return k;
  }
  static std::uint64_t shifted(std::uint64_t k, int dx, int dy, int dz) {
    const auto axis = [&](int a) { return std::int64_t((k >> (21 * (2 - a))) & 2097151u); };
    const std::int64_t x = axis(0) + dx, y = axis(1) + dy, z = axis(2) + dz;
    if (x < 0 || y < 0 || z < 0 || x > 2097151 || y > 2097151 || z > 2097151) return ~std::uint64_t(0);
    return (std::uint64_t(x) << 42) | (std::uint64_t(y) << 21) | std::uint64_t(z);
  }
};

// Per vertex of a layer: whether a vertex of another layer lies in its cell or
// a neighbouring one (cells as large as the reach), so that only those are
// searched: on a dense dress the layers meet along a band, not everywhere.
std::vector<std::uint8_t> near_another_layer(const Points& x, const std::vector<std::uint32_t>& layer, const Cells& cells) {
  const std::size_t n = layer.size();
  struct CellLayer {
    std::uint64_t key;
    std::uint32_t layer;
    auto operator<=>(const CellLayer&) const = default;
  };
  std::vector<CellLayer> occupied(n);
  parallel_for(0, n, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) occupied[v] = {layer[v] > 0 ? cells.key(row3(x, Index(v))) : ~std::uint64_t(0), layer[v]};
  });
  tbb::parallel_sort(occupied.begin(), occupied.end());
  while (!occupied.empty() && occupied.back().key == ~std::uint64_t(0)) occupied.pop_back();  // loose vertices
  occupied.erase(std::unique(occupied.begin(), occupied.end()), occupied.end());
  // Per occupied cell: the least and the greatest layer in it and around it.
  std::vector<std::uint64_t> key;
  for (const CellLayer& c : occupied)
    if (key.empty() || key.back() != c.key) key.push_back(c.key);
  std::vector<std::uint32_t> own_lo(key.size(), std::numeric_limits<std::uint32_t>::max()), own_hi(key.size(), 0);
  for (std::size_t i = 0, c = 0; i < occupied.size(); ++i) {
    while (key[c] != occupied[i].key) ++c;
    own_lo[c] = std::min(own_lo[c], occupied[i].layer);
    own_hi[c] = std::max(own_hi[c], occupied[i].layer);
  }
  std::vector<std::uint32_t> lo = own_lo, hi = own_hi;
  parallel_for(0, key.size(), 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c)
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto it = std::lower_bound(key.begin(), key.end(), Cells::shifted(key[c], dx, dy, dz));
            if (it == key.end() || *it != Cells::shifted(key[c], dx, dy, dz)) continue;
            const std::size_t o = std::size_t(it - key.begin());
            lo[c] = std::min(lo[c], own_lo[o]);
            hi[c] = std::max(hi[c], own_hi[o]);
          }
  });
  std::vector<std::uint8_t> near(n, 0);
  parallel_for(0, n, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      if (layer[v] == 0) continue;
      const std::size_t c = std::size_t(std::lower_bound(key.begin(), key.end(), cells.key(row3(x, Index(v)))) - key.begin());
      near[v] = lo[c] < layer[v] || hi[c] > layer[v];
    }
  });
  return near;
}

// The unit direction away from body A at p: from its closest point, turned by
// the closest triangle's normal where p is inside (a sunk vertex); on the
// surface, that normal.
Vec3 outward(const BodySurface& body, const Vec3& p) {
  const ClosestPoint cp = body.closest(p);
  const Vec3 away = p - cp.point;
  const double len = away.norm();
  if (!(len > 1e-9 * (1.0 + p.norm()))) return cp.normal;
  return (away.dot(cp.normal) < 0.0 ? -1.0 : 1.0) * away / len;
}

Vec3 triangle_normal(const LayerCover& c, const Points& x) {
  const Vec3 a = row3(x, c.outer[0]), b = row3(x, c.outer[1]), d = row3(x, c.outer[2]);
  const Vec3 m = (b - a).cross(d - a);
  return c.flip ? Vec3(-m) : m;
}

}  // namespace

std::pair<double, Vec3> cover_height(const LayerCover& c, const Points& positions) {
  const Vec3 m = triangle_normal(c, positions);
  const double len = m.norm();
  if (!(len > 0.0)) return {std::numeric_limits<double>::infinity(), Vec3::Zero()};
  Vec3 q = Vec3::Zero();
  for (int k = 0; k < 3; ++k) q += c.weight[std::size_t(k)] * row3(positions, c.outer[std::size_t(k)]);
  const Vec3 unit = m / len;
  return {(q - row3(positions, c.inner)).dot(unit), unit};
}

std::vector<LayerCover> bind_layer_order(const Garment& g, const std::vector<std::uint32_t>& vertex_layer,
                                         const BodySurface& body_a, double reach, double gap) {
  std::vector<LayerCover> covers;
  const std::size_t n = g.vertex_count();
  if (vertex_layer.size() != n || n == 0 || !(reach > 0.0)) return covers;
  const std::uint32_t layers = *std::max_element(vertex_layer.begin(), vertex_layer.end());
  if (layers < 2) return covers;
  const Cells cells{g.positions.colwise().minCoeff().transpose(), reach};
  const std::vector<std::uint8_t> near = near_another_layer(g.positions, vertex_layer, cells);
  std::unique_ptr<RTCDeviceTy, void (*)(RTCDevice)> device(rtcNewDevice(nullptr), rtcReleaseDevice);
  if (!device) throw Error("layers: Embree could not start");
  std::vector<std::vector<Index>> candidates_of(std::size_t(layers) + 1);
  for (std::size_t v = 0; v < n; ++v)
    if (near[v]) candidates_of[vertex_layer[v]].push_back(Index(v));
  for (std::uint32_t layer = 1; layer <= layers; ++layer) {
    const std::vector<Index>& candidates = candidates_of[layer];
    if (candidates.empty()) continue;
    // The other layers' faces within a cell of the candidates' cells.
    std::vector<std::uint64_t> own;
    for (Index v : candidates) own.push_back(cells.key(row3(g.positions, v)));
    std::sort(own.begin(), own.end());
    own.erase(std::unique(own.begin(), own.end()), own.end());
    std::vector<std::uint64_t> around;
    for (const std::uint64_t k : own)
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) around.push_back(Cells::shifted(k, dx, dy, dz));
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    const auto close_to_candidates = [&](const Vec3& p) { return std::binary_search(around.begin(), around.end(), cells.key(p)); };
    // Their fan triangles (corners in the garment's numbering), for rays.
    const std::vector<std::array<Index, 3>> others = gather_in_blocks<std::array<Index, 3>>(
        g.faces.rows(), 4096, [&](std::size_t first, std::size_t last, std::vector<std::array<Index, 3>>& out) {
          for (std::size_t f = first; f < last; ++f) {
            const auto face = g.faces.row(f);
            const bool other_layer = std::all_of(face.begin(), face.end(), [&](Index v) {
              return vertex_layer[v] != 0 && vertex_layer[v] != layer;
            });
            if (!other_layer || !close_to_candidates(row3(g.positions, face[0]))) continue;
            for (std::size_t k = 1; k + 1 < face.size(); ++k) out.push_back({face[0], face[k], face[k + 1]});
          }
        });
    if (others.empty()) continue;
    EmbreeScene scene(device.get(), RTC_BUILD_QUALITY_LOW);  // built once, a ray per candidate
    scene.add_triangles(g.positions, others, "layers");
    scene.commit("layers");
    const std::vector<LayerCover> found = gather_in_blocks<LayerCover>(
        candidates.size(), 1024, [&](std::size_t first, std::size_t last, std::vector<LayerCover>& out) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        for (std::size_t k = first; k < last; ++k) {
          // The other layer straight out from the vertex, away from body A.
          const Vec3 p = row3(g.positions, candidates[k]), away = outward(body_a, p);
          RTCRayHit rh = make_ray(p, away);
          rh.ray.tfar = static_cast<float>(reach);
          rtcIntersect1(scene.get(), &ctx, &rh);
          if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
          const auto& t = others[rh.hit.primID];
          LayerCover c{candidates[k], t, {1.0 - double(rh.hit.u) - double(rh.hit.v), double(rh.hit.u), double(rh.hit.v)}, 0.0,
                       false};
          for (double& w : c.weight) w = std::clamp(w, 0.0, 1.0);
          c.flip = triangle_normal(c, g.positions).dot(away) < 0.0;
          const double height = cover_height(c, g.positions).first;
          if (!(height > 0.0 && std::isfinite(height))) continue;
          c.keep = std::min(height, gap);
          out.push_back(c);
        }
      });
    covers.insert(covers.end(), found.begin(), found.end());
  }
  std::sort(covers.begin(), covers.end(), [](const LayerCover& a, const LayerCover& b) { return a.inner < b.inner; });
  return covers;
}

}  // namespace refit
