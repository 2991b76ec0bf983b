#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/spatial_order.hpp>
#include <refit/core/topology.hpp>
#include <refit/core/union_find.hpp>
#include <refit/core/weld.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/samples.hpp>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <tuple>

namespace refit {

namespace {
using namespace sampling;
constexpr std::size_t kAgentGrain = 2048;
constexpr std::uint32_t kMaxCell = (1u << 21) - 1;

void check_garment(const Garment& g) {
  const std::size_t n = g.vertex_count();
  for (std::size_t i = 0; i < n; ++i)
    if (!g.positions.row(static_cast<Eigen::Index>(i)).allFinite())
      throw Error("surface: garment vertex " + std::to_string(i + 1) + " is not finite");
  for (const Csr* c : {&g.faces, &g.lines, &g.points})
    for (Index v : c->indices)
      if (v >= n) throw Error("surface: garment element refers to vertex " + std::to_string(v + 1) + " of " + std::to_string(n));
}

}  // namespace

void check_finite(const Points& points, const std::string& what) {
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    if (!points.row(i).allFinite())
      throw Error("surface: " + what + " row " + std::to_string(i + 1) + " is not finite");
}

std::array<std::uint32_t, 3> VoxelGrid::cell(const Vec3& p) const {
  std::array<std::uint32_t, 3> c{};
  for (int d = 0; d < 3; ++d) {
    const double x = std::floor((p[d] - origin[d]) / h);
    c[d] = x <= 0.0 ? 0u : (x >= kMaxCell ? kMaxCell : static_cast<std::uint32_t>(x));
  }
  return c;
}

Vec3 VoxelGrid::centre(const std::array<std::uint32_t, 3>& c) const {
  return origin + h * Vec3(c[0] + 0.5, c[1] + 0.5, c[2] + 0.5);
}

std::uint64_t VoxelGrid::morton(const std::array<std::uint32_t, 3>& c) {
  return spread3(c[0]) | (spread3(c[1]) << 1) | (spread3(c[2]) << 2);
}

sampling::SampleKey sample_key(const VoxelGrid& grid, const Vec3& p, std::uint64_t id, std::uint32_t layer) {
  const auto c = grid.cell(p);
  const float d2 = static_cast<float>((p - grid.centre(c)).squaredNorm());
  return {VoxelGrid::morton(c), (std::uint64_t(std::bit_cast<std::uint32_t>(d2)) << 32) | id, layer};
}

Points GarmentAgents::positions(const Points& x) const {
  Points out(static_cast<Eigen::Index>(size()), 3);
  parallel_for(0, size(), kAgentGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      Vec3 p = Vec3::Zero();
      for (int k = 0; k < 3; ++k) p += weight[i][k] * row3(x, vertex[i][k]);
      out.row(static_cast<Eigen::Index>(i)) = p.transpose();
    }
  });
  return out;
}

std::pair<double, double> surface_measure(const Garment& g) {
  check_garment(g);
  const Points& x = g.positions;
  const double area = deterministic_sum(0, g.faces.rows(), kAgentGrain, 0.0, [&](std::size_t f) {
    auto r = g.faces.row(f);
    double a = 0.0;
    for (std::size_t t = 1; t + 1 < r.size(); ++t) a += tri_area(row3(x, r[0]), row3(x, r[t]), row3(x, r[t + 1]));
    return a;
  });
  const double length = deterministic_sum(0, g.lines.rows(), kAgentGrain, 0.0, [&](std::size_t l) {
    auto r = g.lines.row(l);
    double s = 0.0;
    for (std::size_t t = 0; t + 1 < r.size(); ++t) s += (row3(x, r[t + 1]) - row3(x, r[t])).norm();
    return s;
  });
  return {area, length};
}

double auto_voxel_size(const Garment& g, std::size_t agent_budget) {
  if (agent_budget == 0) throw Error("surface: the agent budget must be at least 1");
  const auto [area, length] = surface_measure(g);
  if (g.vertex_count() == 0) return auto_voxel_size(area, length, std::nullopt, agent_budget);
  const Vec3 ext = g.positions.colwise().maxCoeff() - g.positions.colwise().minCoeff();
  return auto_voxel_size(area, length, ext, agent_budget);
}

double auto_voxel_size(double area, double length, const std::optional<Vec3>& extent, std::size_t agent_budget) {
  if (agent_budget == 0) throw Error("surface: the agent budget must be at least 1");
  const double b = static_cast<double>(agent_budget) / 1.5;
  // b h^2 - L h - A = 0.
  double h = (length + std::sqrt(length * length + 4.0 * b * area)) / (2.0 * b);
  if (!(h > 0.0)) {
    if (!extent) throw Error("surface: the garment has no vertices");
    h = extent->norm() / std::cbrt(static_cast<double>(agent_budget));
    if (!(h > 0.0)) h = 1.0;  // every vertex at one point: any size works
  }
  return h;
}

VoxelGrid make_voxel_grid(const Garment& g, const Points& extra, double h) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  if (g.vertex_count() > 0) {
    lo = g.positions.colwise().minCoeff().transpose();
    hi = g.positions.colwise().maxCoeff().transpose();
  }
  return make_voxel_grid(lo, hi, extra, h);
}

VoxelGrid make_voxel_grid(Vec3 lo, Vec3 hi, const Points& extra, double h) {
  if (!(h > 0.0) || !std::isfinite(h)) throw Error("surface: the voxel size must be positive and finite");
  if (extra.rows() > 0) {
    lo = lo.cwiseMin(extra.colwise().minCoeff().transpose());
    hi = hi.cwiseMax(extra.colwise().maxCoeff().transpose());
  }
  if (!lo.allFinite() || !hi.allFinite()) throw Error("surface: nothing to sample (no finite positions)");
  if (((hi - lo) / h).maxCoeff() >= kMaxCell)
    throw Error("surface: voxel size " + std::to_string(h) + " is too small for the garment's bounding box");
  VoxelGrid grid;
  grid.origin = lo;
  grid.h = h;
  return grid;
}

std::vector<std::uint32_t> garment_layers(const Garment& g, double min_area, double join_distance) {
  check_garment(g);
  const std::size_t n = g.vertex_count();
  const Points& x = g.positions;
  std::vector<Index> parent(n);
  std::iota(parent.begin(), parent.end(), Index{0});
  for (const Csr* c : {&g.faces, &g.lines, &g.points})
    for (std::size_t e = 0; e < c->rows(); ++e) {
      auto r = c->row(e);
      for (std::size_t k = 1; k < r.size(); ++k) unite_roots(parent, r[0], r[k]);
    }
  // Coincident vertices welded only when the faces are in several pieces (most
  // garments are one: welding a million vertices costs about 50 ms).
  bool several = false;
  for (std::size_t f = 1; f < g.faces.rows() && !several; ++f)
    several = find_root(parent, g.faces.row(f)[0]) != find_root(parent, g.faces.row(0)[0]);
  std::vector<Index> weld(n);
  std::iota(weld.begin(), weld.end(), Index{0});
  if (several) {
    weld = weld_points(x, 1e-6 * bounding_box_diagonal(x));
    for (std::size_t v = 0; v < n; ++v) unite_roots(parent, Index(v), weld[v]);
  }
  std::vector<double> face_area(g.faces.rows(), 0.0);
  parallel_for(0, g.faces.rows(), kAgentGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) {
      auto r = g.faces.row(f);
      for (std::size_t t = 1; t + 1 < r.size(); ++t)
        face_area[f] += tri_area(row3(x, r[0]), row3(x, r[t]), row3(x, r[t + 1]));
    }
  });
  const auto piece_area = [&] {
    std::vector<double> area(n, 0.0);
    for (std::size_t f = 0; f < g.faces.rows(); ++f) area[find_root(parent, g.faces.row(f)[0])] += face_area[f];
    return area;
  };
  std::vector<double> area = piece_area();
  const auto is_layer = [&](double a) { return a > 0.0 && a >= min_area; };
  // Two pieces or more: join those whose face boundaries (edges of one face,
  // on the welded vertices) come within join_distance of each other.
  if (join_distance > 0.0 && std::count_if(area.begin(), area.end(), is_layer) >= 2) {
    const std::vector<Index> boundary = boundary_vertices(g, weld);
    Points bp(static_cast<Eigen::Index>(boundary.size()), 3);
    for (std::size_t i = 0; i < boundary.size(); ++i) bp.row(Eigen::Index(i)) = x.row(boundary[i]);
    const std::vector<Index> near = weld_points(bp, join_distance);
    for (std::size_t i = 0; i < boundary.size(); ++i) unite_roots(parent, boundary[i], boundary[near[i]]);
    area = piece_area();
  }
  std::vector<std::uint32_t> label(n, 0), of_root(n, 0);
  std::uint32_t next = 1;
  for (std::size_t v = 0; v < n; ++v) {
    const Index r = find_root(parent, Index(v));
    if (!is_layer(area[r])) continue;
    if (of_root[r] == 0) of_root[r] = next++;
    label[v] = of_root[r];
  }
  return label;
}

GarmentAgents select_agents(const Garment& g, const VoxelGrid& grid, const std::vector<VoxelLayer>& skip,
                            const std::vector<std::uint32_t>& vertex_layer) {
  if (!vertex_layer.empty() && vertex_layer.size() != g.vertex_count())
    throw Error("surface: " + std::to_string(vertex_layer.size()) + " vertex layers for " +
                std::to_string(g.vertex_count()) + " vertices");
  check_garment(g);
  const Points& x = g.positions;
  const double spacing = 0.5 * grid.h;
  const std::size_t nv = g.vertex_count(), nf = g.faces.rows(), nl = g.lines.rows();

  // Sample counts per face and per line, then prefix offsets: sample s is
  // vertex s, then face samples, then line samples.
  std::vector<std::uint64_t> face_off(nf + 1, 0), line_off(nl + 1, 0);
  std::vector<std::uint32_t> face_m;  // subdivision of each fan triangle, flattened per face corner
  face_m.resize(g.faces.indices.size());
  parallel_for(0, nf, kAgentGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) {
      auto r = g.faces.row(f);
      std::uint64_t c = 0;
      for (std::size_t t = 1; t + 1 < r.size(); ++t) {
        const std::uint32_t m = face_subdivision(tri_area(row3(x, r[0]), row3(x, r[t]), row3(x, r[t + 1])), spacing);
        face_m[g.faces.offsets[f] + t] = m;
        c += std::uint64_t(m) * m;
      }
      face_off[f + 1] = c;
    }
  });
  std::vector<std::uint32_t> line_m(g.lines.indices.size(), 0);
  parallel_for(0, nl, kAgentGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t l = b; l < e; ++l) {
      auto r = g.lines.row(l);
      std::uint64_t c = 0;
      for (std::size_t t = 0; t + 1 < r.size(); ++t) {
        const std::uint32_t m = segment_samples((row3(x, r[t + 1]) - row3(x, r[t])).norm(), spacing);
        line_m[g.lines.offsets[l] + t] = m;
        // m pieces: the m-1 inner division points (the ends are vertex samples).
        c += m > 0 ? m - 1 : 0;
      }
      line_off[l + 1] = c;
    }
  });
  for (std::size_t f = 0; f < nf; ++f) face_off[f + 1] += face_off[f];
  for (std::size_t l = 0; l < nl; ++l) line_off[l + 1] += line_off[l];
  const std::uint64_t total = nv + face_off[nf] + line_off[nl];
  if (total >= (1ull << 32)) throw Error("surface: more than 2^32 samples; use a larger voxel size");

  auto visit_face = [&](std::size_t f, auto&& emit) {
    auto r = g.faces.row(f);
    std::uint64_t k = nv + face_off[f];
    for (std::size_t t = 1; t + 1 < r.size(); ++t) {
      const std::uint32_t m = face_m[g.faces.offsets[f] + t];
      for (std::uint32_t s = 0; s < m * m; ++s) emit(k++, Sample{{r[0], r[t], r[t + 1]}, lattice_point(m, s)});
    }
  };
  auto visit_line = [&](std::size_t l, auto&& emit) {
    auto r = g.lines.row(l);
    std::uint64_t k = nv + face_off[nf] + line_off[l];
    for (std::size_t t = 0; t + 1 < r.size(); ++t) {
      const std::uint32_t m = line_m[g.lines.offsets[l] + t];
      for (std::uint32_t s = 1; s < m; ++s) {
        const double u = double(s) / m;
        emit(k++, Sample{{r[t], r[t + 1], r[t]}, {1.0 - u, u, 0.0}});
      }
    }
  };
  auto position = [&](const Sample& s) { return sample_position(s, row3(x, s.v[0]), row3(x, s.v[1]), row3(x, s.v[2])); };

  std::vector<SampleKey> keys(total);
  auto key_of = [&](std::uint64_t id, const Sample& s) {
    keys[id] = sample_key(grid, position(s), id, vertex_layer.empty() ? 0u : vertex_layer[s.v[0]]);
  };
  parallel_for(0, nv, kAgentGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) key_of(i, Sample{{Index(i), Index(i), Index(i)}, {1.0, 0.0, 0.0}});
  });
  parallel_for(0, nf, kAgentGrain / 4, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) visit_face(f, key_of);
  });
  parallel_for(0, nl, kAgentGrain / 4, [&](std::size_t b, std::size_t e) {
    for (std::size_t l = b; l < e; ++l) visit_line(l, key_of);
  });
  // Keys are unique (the sample number is in them), so the sorted order, and the
  // winner of each voxel, do not depend on the thread count.
  tbb::parallel_sort(keys.begin(), keys.end());

  std::vector<std::uint64_t> winners;  // sample numbers
  std::vector<std::uint32_t> winner_layer;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (i > 0 && keys[i].voxel == keys[i - 1].voxel && keys[i].layer == keys[i - 1].layer) continue;
    if (std::binary_search(skip.begin(), skip.end(), VoxelLayer{keys[i].voxel, keys[i].layer})) continue;
    winners.push_back(keys[i].rank & 0xffffffffULL);
    winner_layer.push_back(keys[i].layer);
  }
  GarmentAgents out;
  out.samples = total;
  const std::size_t na = winners.size();
  out.vertex.resize(na);
  out.weight.resize(na);
  out.voxel.resize(na);
  out.layer = std::move(winner_layer);
  parallel_for(0, na, kAgentGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const std::uint64_t id = winners[a];
      Sample s{};
      if (id < nv) {
        s = Sample{{Index(id), Index(id), Index(id)}, {1.0, 0.0, 0.0}};
      } else if (id < nv + face_off[nf]) {
        const std::size_t f = std::upper_bound(face_off.begin(), face_off.end(), id - nv) - face_off.begin() - 1;
        visit_face(f, [&](std::uint64_t k, const Sample& t) { if (k == id) s = t; });
      } else {
        const std::uint64_t j = id - nv - face_off[nf];
        const std::size_t l = std::upper_bound(line_off.begin(), line_off.end(), j) - line_off.begin() - 1;
        visit_line(l, [&](std::uint64_t k, const Sample& t) { if (k == id) s = t; });
      }
      out.vertex[a] = s.v;
      out.weight[a] = s.w;
      out.voxel[a] = VoxelGrid::morton(grid.cell(position(s)));
    }
  });
  return out;
}

Csr build_one_rings(const Points& agents, double radius, const std::vector<std::uint32_t>& layer) {
  const std::size_t n = static_cast<std::size_t>(agents.rows());
  if (!layer.empty() && layer.size() != n)
    throw Error("surface: " + std::to_string(layer.size()) + " agent layers for " + std::to_string(n) + " agents");
  PointTree tree(agents);
  const double r2 = radius * radius;
  const double tiny2 = 1e-18 * r2;
  std::vector<std::vector<Index>> rows(n);
  parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
    std::vector<std::pair<Index, double>> cand;
    std::vector<std::uint8_t> alive;
    for (std::size_t i = b; i < e; ++i) {
      const Vec3 a = row3(agents, Index(i));
      tree.within(a, r2, cand);  // closest first
      alive.assign(cand.size(), 1);
      for (std::size_t k = 0; k < cand.size(); ++k)
        if (cand[k].first == i || cand[k].second <= tiny2) alive[k] = 0;
      std::vector<Index>& ring = rows[i];
      const std::uint32_t own = layer.empty() ? 0u : layer[i];
      for (std::size_t k = 0; k < cand.size(); ++k) {
        if (!alive[k] || (own != 0 && layer[cand[k].first] != own)) continue;
        const Vec3 c = row3(agents, cand[k].first);
        ring.push_back(cand[k].first);
        const Vec3 dir = c - a;
        // Drop every candidate on or beyond the plane through a_c normal to a_c - a (a_c itself too).
        for (std::size_t q = k; q < cand.size(); ++q)
          if (alive[q] && (row3(agents, cand[q].first) - c).dot(dir) >= 0.0) alive[q] = 0;
      }
    }
  });
  Csr out;
  out.offsets.reserve(n + 1);
  for (std::size_t i = 0; i < n; ++i) {
    out.push_row(rows[i]);
    std::vector<Index>().swap(rows[i]);
  }
  return out;
}

struct LayerTrees::Impl {
  PointTree all;
  std::vector<std::unique_ptr<PointTree>> tree;  // per layer (index 0 unused)
  std::vector<std::vector<Index>> index;         // per layer: the points' indices
  explicit Impl(const Points& p) : all(p) {}
};

LayerTrees::LayerTrees(const Points& points, const std::vector<std::uint32_t>& layer) : impl_(std::make_unique<Impl>(points)) {
  const std::uint32_t layers = layer.empty() ? 0u : *std::max_element(layer.begin(), layer.end());
  impl_->tree.resize(layers + 1);
  impl_->index.resize(layers + 1);
  for (std::size_t i = 0; i < layer.size(); ++i)
    if (layer[i] > 0) impl_->index[layer[i]].push_back(Index(i));
  for (std::uint32_t l = 1; l <= layers; ++l) {
    const std::vector<Index>& ix = impl_->index[l];
    Points sub(static_cast<Eigen::Index>(ix.size()), 3);
    for (std::size_t k = 0; k < ix.size(); ++k) sub.row(static_cast<Eigen::Index>(k)) = points.row(ix[k]);
    impl_->tree[l] = std::make_unique<PointTree>(sub);
  }
}

LayerTrees::~LayerTrees() = default;

void LayerTrees::knn(std::uint32_t layer, const Vec3& p, std::size_t k, std::vector<Index>& idx,
                     std::vector<double>& dist2, std::span<const Vec3> hint) const {
  if (layer == 0 || layer >= impl_->tree.size() || impl_->index[layer].empty()) {
    impl_->all.knn(p, k, idx, dist2, hint);
    return;
  }
  impl_->tree[layer]->knn(p, k, idx, dist2, hint);
  for (Index& i : idx) i = impl_->index[layer][i];
}

}  // namespace refit
