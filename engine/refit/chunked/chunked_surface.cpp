// The surface binding's garment passes over a stored garment. Each mirrors its
// in-memory function (agents.cpp, bind.cpp) step by step, in the same order of
// floating-point operations, so the voxel size, the layers and the agents are
// the same bits.
#include <refit/chunked/chunked_surface.hpp>

#include <refit/chunked/chunked_topology.hpp>
#include <refit/chunked/deterministic_sum.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/progress.hpp>
#include <refit/core/union_find.hpp>
#include <refit/core/weld.hpp>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <unordered_map>

namespace refit {
namespace {
using namespace sampling;

constexpr std::size_t kGrain = 2048;  // select_agents' and surface_measure's grain (agents.cpp)

double face_area(const ElementBlock& b, std::size_t f) {
  const std::size_t o = b.rows.offsets[f], k = b.rows.row_size(f);
  double a = 0.0;
  for (std::size_t t = 1; t + 1 < k; ++t) a += tri_area(b.corner(o), b.corner(o + t), b.corner(o + t + 1));
  return a;
}

// Each piece of a block's elements (a face's fan triangles from t = 1, a line's
// segments from t = 0) subdivided m = subdivide(o, t) times, at corner entry
// o + t, and each element's first sample within the block: the sums of count(m).
struct PieceSamples {
  std::vector<std::uint32_t> m;             // per corner entry
  std::vector<std::uint64_t> first_sample;  // per element, and the block's total last
};

template <class Subdivide, class Count>
PieceSamples piece_samples(const ElementBlock& b, std::size_t first_piece, Subdivide&& subdivide, Count&& count) {
  const std::size_t n = b.rows.rows();
  PieceSamples p{std::vector<std::uint32_t>(b.rows.indices.size(), 0), std::vector<std::uint64_t>(n + 1, 0)};
  for (std::size_t e = 0; e < n; ++e) {
    const std::size_t o = b.rows.offsets[e];
    std::uint64_t c = 0;
    for (std::size_t t = first_piece; t + 1 < b.rows.row_size(e); ++t) {
      p.m[o + t] = subdivide(o, t);
      c += count(p.m[o + t]);
    }
    p.first_sample[e + 1] = p.first_sample[e] + c;
  }
  return p;
}

}  // namespace

std::pair<double, double> chunked_surface_measure(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan) {
  // surface_measure's two deterministic sums.
  DeterministicSum area(0, g.face_count(), kGrain), length(0, g.line_count(), kGrain);
  for_each_block(g.faces(), plan.chunk_faces, x, [&](const ElementBlock& b) {
    for (std::size_t f = 0; f < b.rows.rows(); ++f) area.add(b.first + f, face_area(b, f));
  });
  for_each_block(g.lines(), plan.chunk_faces, x, [&](const ElementBlock& b) {
    for (std::size_t l = 0; l < b.rows.rows(); ++l) {
      const std::size_t o = b.rows.offsets[l];
      double s = 0.0;
      for (std::size_t t = 0; t + 1 < b.rows.row_size(l); ++t) s += (b.corner(o + t + 1) - b.corner(o + t)).norm();
      length.add(b.first + l, s);
    }
  });
  return {area.result(), length.result()};
}

double chunked_surface_voxel(const GarmentStore& g, std::pair<double, double> measure, const SurfaceOptions& options) {
  if (options.voxel != 0.0) return options.voxel;
  const std::size_t budget = std::min(options.agent_budget, std::max<std::size_t>(g.vertex_count(), 1000));
  return auto_voxel_size(measure.first, measure.second, Vec3(g.high() - g.low()), budget);
}

std::vector<std::uint32_t> chunked_layers(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan,
                                          double min_area, double join_distance) {
  const std::size_t n = g.vertex_count();
  std::vector<Index> parent(n);
  std::iota(parent.begin(), parent.end(), Index{0});
  for (const CsrFile* c : {&g.faces(), &g.lines(), &g.points()})
    for_each_chunk(*c, plan.chunk_faces, [&](std::size_t, const Csr& rows) {
      for (std::size_t e = 0; e < rows.rows(); ++e) {
        auto r = rows.row(e);
        for (std::size_t k = 1; k < r.size(); ++k) unite_roots(parent, r[0], r[k]);
      }
    });
  // Coincident vertices welded only when the faces are in several pieces.
  bool several = false;
  Index root0 = 0;
  for_each_chunk(g.faces(), plan.chunk_faces, [&](std::size_t first, const Csr& rows) {
    for (std::size_t f = 0; f < rows.rows() && !several; ++f) {
      if (first + f == 0) root0 = find_root(parent, rows.row(0)[0]);
      else several = find_root(parent, rows.row(f)[0]) != root0;
    }
  });
  std::unordered_map<Index, Index> weld;  // vertices welded to another (weld_points' representative)
  if (several) {
    weld = chunked_weld(g, plan, 1e-6 * bounding_box_diagonal(g));
    for (Index v = 0; v < n; ++v) {  // in vertex order, as garment_layers unites
      const auto it = weld.find(v);
      unite_roots(parent, v, it == weld.end() ? v : it->second);
    }
  }
  const auto welded = [&](Index v) {
    const auto it = weld.find(v);
    return it == weld.end() ? v : it->second;
  };
  // Face areas once (kept on disk), summed per piece in face order.
  RecordFile<double> areas(plan.folder);
  for_each_block(g.faces(), plan.chunk_faces, x, [&](const ElementBlock& b) {
    std::vector<double> a(b.rows.rows(), 0.0);
    parallel_for(0, a.size(), kGrain, [&](std::size_t lo, std::size_t hi) {
      for (std::size_t f = lo; f < hi; ++f) a[f] = face_area(b, f);
    });
    areas.write(b.first, std::span<const double>(a));
  });
  const auto piece_area = [&] {
    std::unordered_map<Index, double> area;
    std::vector<double> a;
    for_each_chunk(g.faces(), plan.chunk_faces, [&](std::size_t first, const Csr& rows) {
      areas.read(first, rows.rows(), a);
      for (std::size_t f = 0; f < rows.rows(); ++f) area[find_root(parent, rows.row(f)[0])] += a[f];
    });
    return area;
  };
  std::unordered_map<Index, double> area = piece_area();
  const auto is_layer = [&](double a) { return a > 0.0 && a >= min_area; };
  const auto layer_pieces = [&] {
    std::size_t k = 0;
    for (const auto& [root, a] : area) k += is_layer(a);
    return k;
  };
  // Two pieces or more: join those whose face boundaries (edges of one face,
  // on the welded vertices) come within join_distance of each other.
  if (join_distance > 0.0 && layer_pieces() >= 2) {
    EdgeBuckets edges(plan.folder, g.faces().entries(), std::max<std::size_t>(plan.chunk_vertices * 8, 1 << 12));
    for_each_chunk(g.faces(), plan.chunk_faces, [&](std::size_t, const Csr& rows) {
      for (std::size_t f = 0; f < rows.rows(); ++f) {
        auto r = rows.row(f);
        for (std::size_t k = 0; k < r.size(); ++k) {
          const std::uint64_t a = welded(r[k]), b = welded(r[(k + 1) % r.size()]);
          if (a != b) edges.add(std::min(a, b) << 32 | std::max(a, b));
        }
      }
    });
    std::vector<Index> boundary;
    edges.singles([&](std::uint64_t k) { boundary.insert(boundary.end(), {Index(k >> 32), Index(k & 0xffffffffULL)}); });
    std::sort(boundary.begin(), boundary.end());
    boundary.erase(std::unique(boundary.begin(), boundary.end()), boundary.end());
    Points bp;
    x.gather(boundary, bp);
    const std::vector<Index> near = weld_points(bp, join_distance);
    for (std::size_t i = 0; i < boundary.size(); ++i) unite_roots(parent, boundary[i], boundary[near[i]]);
    area = piece_area();
  }
  flatten_roots(parent);  // then each vertex's label in place
  std::unordered_map<Index, std::uint32_t> of_root;
  std::uint32_t next = 1;
  std::vector<std::uint32_t>& label = parent;  // the same memory, vertex by vertex
  for (Index v = 0; v < n; ++v) {
    const Index r = parent[v];
    const auto it = area.find(r);
    if (it == area.end() || !is_layer(it->second)) {
      label[v] = 0;
      continue;
    }
    auto [slot, fresh] = of_root.try_emplace(r, 0u);
    if (fresh) slot->second = next++;
    label[v] = slot->second;
  }
  return std::move(label);
}

GarmentAgents chunked_select_agents(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan,
                                    const VoxelGrid& grid, const std::vector<VoxelLayer>& skip,
                                    const std::vector<std::uint32_t>& vertex_layer) {
  if (!vertex_layer.empty() && vertex_layer.size() != g.vertex_count())
    throw Error("surface: " + std::to_string(vertex_layer.size()) + " vertex layers for " +
                std::to_string(g.vertex_count()) + " vertices");
  const double spacing = 0.5 * grid.h;
  const std::size_t nv = g.vertex_count();
  const auto layer_of = [&](Index v) { return vertex_layer.empty() ? 0u : vertex_layer[v]; };
  // The best sample of each voxel and layer (select_agents sorts all keys and
  // keeps each voxel's first: the smallest rank, as here).
  struct Best {
    std::uint64_t rank;
    Sample sample;
  };
  using Voxel = std::pair<std::uint64_t, std::uint32_t>;
  struct VoxelHash {
    std::size_t operator()(const Voxel& v) const { return std::hash<std::uint64_t>()(v.first * 0x9E3779B97F4A7C15ULL ^ v.second); }
  };
  using BestMap = std::unordered_map<Voxel, Best, VoxelHash>;
  BestMap best;
  const auto offer = [](BestMap& m, const SampleKey& k, const Sample& s) {
    auto [it, fresh] = m.try_emplace(Voxel{k.voxel, k.layer}, Best{k.rank, s});
    if (!fresh && k.rank < it->second.rank) it->second = Best{k.rank, s};
  };
  const auto merge = [&](BestMap& part) {
    for (auto& [v, b] : part) offer(best, SampleKey{v.first, b.rank, v.second}, b.sample);
    part.clear();
  };
  // In parallel over fixed pieces, each with its own map, merged after (the
  // smallest rank wins whatever the order).
  const auto parallel_offer = [&](std::size_t count, auto&& each) {
    constexpr std::size_t kPiece = 1 << 14;
    std::vector<BestMap> parts((count + kPiece - 1) / kPiece);
    parallel_for(0, parts.size(), 1, [&](std::size_t b, std::size_t e) {
      for (std::size_t p = b; p < e; ++p)
        for (std::size_t i = p * kPiece; i < std::min(count, (p + 1) * kPiece); ++i)
          each(i, [&](const SampleKey& k, const Sample& s) { offer(parts[p], k, s); });
    });
    for (BestMap& part : parts) merge(part);
  };
  std::uint64_t total = nv;
  for_each_chunk(g.positions(), plan.chunk_vertices, [&](std::size_t first, const Points& rows) {
    parallel_offer(std::size_t(rows.rows()), [&](std::size_t i, auto&& emit) {
      const Index v = Index(first + i);
      const Sample s{{v, v, v}, {1.0, 0.0, 0.0}};
      const Vec3 p = row3(rows, Index(i));
      emit(sample_key(grid, sample_position(s, p, p, p), v, layer_of(v)), s);
    });
  });
  // Face samples: numbered after the vertices, face by face.
  for_each_block(g.faces(), plan.chunk_faces, x, [&](const ElementBlock& b) {
    const std::size_t nf = b.rows.rows();
    const PieceSamples p = piece_samples(
        b, 1,
        [&](std::size_t o, std::size_t t) {
          return face_subdivision(tri_area(b.corner(o), b.corner(o + t), b.corner(o + t + 1)), spacing);
        },
        [](std::uint32_t m) { return std::uint64_t(m) * m; });  // an m x m lattice
    parallel_offer(nf, [&](std::size_t f, auto&& emit) {
      const auto r = b.rows.row(f);
      const std::size_t o = b.rows.offsets[f];
      std::uint64_t k = total + p.first_sample[f];
      for (std::size_t t = 1; t + 1 < r.size(); ++t)
        for (std::uint32_t q = 0; q < p.m[o + t] * p.m[o + t]; ++q) {
          const Sample s{{r[0], r[t], r[t + 1]}, lattice_point(p.m[o + t], q)};
          emit(sample_key(grid, sample_position(s, b.corner(o), b.corner(o + t), b.corner(o + t + 1)), k++, layer_of(r[0])), s);
        }
    });
    total += p.first_sample[nf];
  });
  for_each_block(g.lines(), plan.chunk_faces, x, [&](const ElementBlock& b) {
    const std::size_t nl = b.rows.rows();
    const PieceSamples p = piece_samples(
        b, 0,
        [&](std::size_t o, std::size_t t) { return segment_samples((b.corner(o + t + 1) - b.corner(o + t)).norm(), spacing); },
        [](std::uint32_t m) { return std::uint64_t(m > 0 ? m - 1 : 0); });  // the inner division points
    parallel_offer(nl, [&](std::size_t l, auto&& emit) {
      const auto r = b.rows.row(l);
      const std::size_t o = b.rows.offsets[l];
      std::uint64_t k = total + p.first_sample[l];
      for (std::size_t t = 0; t + 1 < r.size(); ++t)
        for (std::uint32_t q = 1; q < p.m[o + t]; ++q) {
          const double u = double(q) / p.m[o + t];
          const Sample s{{r[t], r[t + 1], r[t]}, {1.0 - u, u, 0.0}};
          emit(sample_key(grid, sample_position(s, b.corner(o + t), b.corner(o + t + 1), b.corner(o + t)), k++, layer_of(r[t])), s);
        }
    });
    total += p.first_sample[nl];
  });
  if (total >= (1ull << 32)) throw Error("surface: more than 2^32 samples; use a larger voxel size");

  std::vector<std::pair<Voxel, Best>> winners(best.begin(), best.end());
  std::sort(winners.begin(), winners.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  GarmentAgents out;
  out.samples = total;
  std::vector<Index> ids;
  for (const auto& [v, b] : winners) {
    if (std::binary_search(skip.begin(), skip.end(), VoxelLayer{v.first, v.second})) continue;
    out.vertex.push_back(b.sample.v);
    out.weight.push_back(b.sample.w);
    out.layer.push_back(v.second);
    ids.insert(ids.end(), b.sample.v.begin(), b.sample.v.end());
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  Points p;
  x.gather(ids, p);
  const auto at = [&](Index v) { return row3(p, Index(std::lower_bound(ids.begin(), ids.end(), v) - ids.begin())); };
  for (std::size_t a = 0; a < out.vertex.size(); ++a) {
    const Sample s{out.vertex[a], out.weight[a]};
    out.voxel.push_back(VoxelGrid::morton(grid.cell(sample_position(s, at(s.v[0]), at(s.v[1]), at(s.v[2])))));
  }
  return out;
}

SurfaceGarmentPart chunked_surface_part(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan,
                                        const Points& features, const SurfaceOptions& options,
                                        const SurfaceAttachment& attachment, std::vector<std::uint32_t>& vertex_layer) {
  check_surface_options(options);
  Stopwatch clock;
  SurfaceGarmentPart part;
  part.voxel_auto = options.voxel == 0.0;
  const std::pair<double, double> measure = chunked_surface_measure(g, x, plan);
  part.voxel = chunked_surface_voxel(g, measure, options);
  check_agent_count(measure.first, measure.second, Vec3(g.high() - g.low()), part.voxel, options.max_agents);
  part.grid = make_voxel_grid(g.low(), g.high(), features, part.voxel);
  part.vertex_count = g.vertex_count();
  vertex_layer.clear();
  if (options.layers)
    vertex_layer = chunked_layers(g, x, plan, options.layer_min_area * part.voxel * part.voxel, options.layer_join * part.voxel);
  part.layers = vertex_layer.empty() ? 0 : *std::max_element(vertex_layer.begin(), vertex_layer.end());
  std::function<std::uint32_t(Index)> layer_of;
  if (!vertex_layer.empty()) layer_of = [&](Index v) { return vertex_layer[v]; };
  part.feature_layer = feature_layers(std::size_t(features.rows()), attachment, layer_of);
  part.ms.sample = clock.ms();
  clock.reset();
  part.agents = chunked_select_agents(g, x, plan, part.grid, feature_skip(part.grid, features, part.feature_layer), vertex_layer);
  // Their positions as GarmentAgents::positions sums them, on the gathered vertices.
  std::vector<Index> ids;
  for (const auto& v : part.agents.vertex) ids.insert(ids.end(), v.begin(), v.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  Points p;
  x.gather(ids, p);
  GarmentAgents local = part.agents;
  for (auto& v : local.vertex)
    for (Index& i : v) i = Index(std::lower_bound(ids.begin(), ids.end(), i) - ids.begin());
  part.agent_positions = local.positions(p);
  part.ms.agents = clock.ms();
  return part;
}

}  // namespace refit
