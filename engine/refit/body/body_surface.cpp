// Body surface queries through Embree 3. Embree (float) only finds candidate
// triangles and ray hits; every distance and every inside/outside decision near
// the surface is made in double on the body's own positions.
#include <refit/body/body_surface.hpp>

#include <refit/body/embree_scene.hpp>
#include <refit/body/centre_tree.hpp>
#include <refit/core/topology.hpp>
#include <refit/core/union_find.hpp>

#include <refit/core/parallel.hpp>

#include <tbb/task_arena.h>
#include <refit/body/embree_ray.hpp>
#include <refit/core/error.hpp>

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace refit {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Where on a triangle the closest point lies: the face, one of its corners, or
// one of its edges (edge k runs from corner k to corner k+1).
enum Region : int { kFace = 0, kVertex0 = 1, kEdge0 = 4 };

struct TrianglePoint {
  Vec3 point;
  int region;
};

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5),
// in double, also telling which feature (face, edge, vertex) it lies on.
TrianglePoint closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, kVertex0 + 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {b, kVertex0 + 1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return {a + (d1 / (d1 - d3)) * ab, kEdge0 + 0};
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {c, kVertex0 + 2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return {a + (d2 / (d2 - d6)) * ac, kEdge0 + 2};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return {b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b), kEdge0 + 1};
  const double denom = 1.0 / (va + vb + vc);
  return {a + ab * (vb * denom) + ac * (vc * denom), kFace};
}

// Fixed, irrational-looking ray directions so that rays rarely run along mesh
// edges or axis-aligned features.
const std::array<Vec3, 5>& ray_directions() {
  static const std::array<Vec3, 5> dirs = [] {
    std::array<Vec3, 5> d = {Vec3(0.5773, 0.6183, 0.5332), Vec3(-0.7071, 0.1234, 0.6963),
                             Vec3(0.2113, -0.9127, 0.3498), Vec3(-0.3761, -0.4193, -0.8263),
                             Vec3(0.8614, 0.0957, -0.4989)};
    for (auto& v : d) v.normalize();
    return d;
  }();
  return dirs;
}

struct RayHit {
  float t;
  Index tri;
  int side;  // +1 leaving (along the face normal), -1 entering, 0 grazing
};

constexpr int kMaxHits = 256;

// Intersect context extended with a hit list: the context filter records every
// hit along the ray and rejects it, so Embree reports all crossings, not only
// the first.
struct CollectContext {
  RTCIntersectContext ctx;
  const Points* face_normal = nullptr;
  Vec3 dir = Vec3::Zero();
  std::array<RayHit, kMaxHits> hits;
  int count = 0;
  bool overflow = false;
};

void collect_filter(const RTCFilterFunctionNArguments* args) {
  auto* c = reinterpret_cast<CollectContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    args->valid[i] = 0;  // reject, so traversal goes on to the next hit
    if (c->count >= kMaxHits) {
      c->overflow = true;
      continue;
    }
    const Index tri = RTCHitN_primID(args->hit, args->N, i);
    const double s = c->face_normal->row(tri).dot(c->dir);
    c->hits[static_cast<std::size_t>(c->count++)] = {RTCRayN_tfar(args->ray, args->N, i), tri,
                                                     s > 0.0 ? 1 : (s < 0.0 ? -1 : 0)};
  }
}

struct PointQueryData {
  const std::vector<std::array<Vec3, 3>>* corners;  // per triangle
  const std::vector<std::uint8_t>* degenerate;
  Vec3 p;
  double best_d2 = kInf;
  Index tri = 0;
  Vec3 point = Vec3::Zero();
  int region = 0;
};

// The closest point of triangle t to d.p; nullopt for a degenerate triangle
// (its points lie on neighbours' edges anyway).
std::optional<TrianglePoint> triangle_point(const PointQueryData& d, Index t) {
  if ((*d.degenerate)[t]) return std::nullopt;
  const auto& c = (*d.corners)[t];
  return closest_on_triangle(d.p, c[0], c[1], c[2]);
}

bool point_query_callback(RTCPointQueryFunctionArguments* args) {
  auto* d = static_cast<PointQueryData*>(args->userPtr);
  const Index t = args->primID;
  const std::optional<TrianglePoint> tp = triangle_point(*d, t);
  if (!tp) return false;
  const double d2 = (tp->point - d->p).squaredNorm();
  if (d2 < d->best_d2 || (d2 == d->best_d2 && t < d->tri)) {  // ties: lowest index, for determinism
    d->best_d2 = d2;
    d->tri = t;
    d->point = tp->point;
    d->region = tp->region;
    // Slightly larger than the double distance so float rounding never culls
    // an equally close triangle.
    args->query->radius = static_cast<float>(std::sqrt(d2) * (1.0 + 1e-6)) + 1e-30f;
    return true;
  }
  return false;
}

// closer_than's search: stops (radius 0) at the first triangle that passes
// closest_within's two tests, the clamp to max_distance and distance < max_distance.
struct CloserThanData {
  PointQueryData query;
  double max_distance;
  bool found = false;
  Index tri = 0;
};

bool closer_than_test(const CloserThanData& d, Index t) {
  const std::optional<TrianglePoint> tp = triangle_point(d.query, t);
  if (!tp) return false;
  const double d2 = (tp->point - d.query.p).squaredNorm();
  return d2 <= d.max_distance * d.max_distance && std::sqrt(d2) < d.max_distance;
}

bool closer_than_callback(RTCPointQueryFunctionArguments* args) {
  auto* d = static_cast<CloserThanData*>(args->userPtr);
  if (d->found || !closer_than_test(*d, args->primID)) return false;
  d->found = true;
  d->tri = args->primID;
  args->query->radius = 0.0f;
  return true;
}

}  // namespace

struct BodyTopology {
  std::vector<std::array<Index, 3>> triangles;  // what it was made from
  Index vertex_count = 0;
  // The faces' edges (slot 3t + k: edge k of triangle t) grouped by undirected
  // edge, each group in slot order: group g is edge_slot[edge_start[g] ..
  // edge_start[g + 1]).
  std::vector<Index> edge_slot;
  std::vector<std::size_t> edge_start;
  std::vector<std::uint8_t> edge_ok;    // per slot: its edge has exactly two faces with opposite edge directions
  std::vector<std::uint8_t> vertex_ok;  // every edge around the vertex is ok
  bool oriented = false;                // closed, manifold, consistently oriented
  Csr neighbours;                       // per vertex, the other ends of its edges (sorted)
};

namespace {

std::shared_ptr<const BodyTopology> make_topology(const std::vector<std::array<Index, 3>>& triangles, Index nv) {
  auto topo = std::make_shared<BodyTopology>();
  BodyTopology& m = *topo;
  m.triangles = triangles;
  m.vertex_count = nv;
  const Index nt = static_cast<Index>(triangles.size());
  {
    Garment surface;  // the body's triangles as faces, for the garments' vertex adjacency
    surface.positions = Points::Zero(nv, 3);
    for (const auto& t : triangles) surface.faces.push_row(t);
    m.neighbours = vertex_adjacency(surface);
  }
  // Edge incidence: sort directed edges by undirected key; a good edge has exactly
  // two faces traversing it in opposite directions.
  struct DirEdge {
    std::uint64_t key;
    Index slot;  // 3t + k
    bool forward;
  };
  std::vector<DirEdge> edges;
  edges.reserve(3 * static_cast<std::size_t>(nt));
  for (Index t = 0; t < nt; ++t)
    for (Index k = 0; k < 3; ++k) {
      const Index a = triangles[t][k], b = triangles[t][(k + 1) % 3];
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
      edges.push_back({key, 3 * t + k, a < b});
    }
  std::sort(edges.begin(), edges.end(), [](const DirEdge& x, const DirEdge& y) {
    return x.key < y.key || (x.key == y.key && x.slot < y.slot);
  });
  m.edge_slot.resize(edges.size());
  m.edge_ok.assign(3 * static_cast<std::size_t>(nt), 0);
  m.vertex_ok.assign(nv, 1);
  bool all_ok = true;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    const bool ok = (j - i == 2) && edges[i].forward != edges[i + 1].forward;
    m.edge_start.push_back(i);
    for (std::size_t e = i; e < j; ++e) {
      m.edge_slot[e] = edges[e].slot;
      m.edge_ok[edges[e].slot] = ok ? 1 : 0;
    }
    if (!ok) {
      all_ok = false;
      m.vertex_ok[static_cast<Index>(edges[i].key >> 32)] = 0;
      m.vertex_ok[static_cast<Index>(edges[i].key & 0xFFFFFFFFu)] = 0;
    }
    i = j;
  }
  m.edge_start.push_back(edges.size());
  m.oriented = all_ok;
  return topo;
}

}  // namespace

struct BodySurface::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  Points vertices;
  std::vector<std::array<Index, 3>> triangles;
  // Each triangle's corners side by side: a point query reads one triangle's from
  // one place, not from the three columns of `vertices` at three rows.
  std::vector<std::array<Vec3, 3>> corners;
  Points face_normal;                     // unit, zero for degenerate triangles
  std::vector<std::uint8_t> degenerate;
  Points edge_normal;                     // row 3t+k: sum of the normals of the faces on edge k of t
  Points vertex_normal;                   // angle-weighted pseudonormal
  double orientation = 1.0;               // +1 when normals point outward (positive volume)
  double near_tolerance = 0.0;            // below this distance the pseudonormal decides inside
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // body bounding box
  // Inside/outside grid, built on the first inside test: cells that touch no
  // triangle's bounding box get the label of their connected region (one ray
  // vote per region), so most points far from the surface need no ray at all.
  enum : std::uint8_t { kBoundary = 0, kOutside = 1, kInside = 2 };
  mutable std::once_flag grid_once;
  mutable std::vector<std::uint8_t> grid;
  mutable Vec3 grid_lo = Vec3::Zero();
  mutable double grid_h = 1.0;
  mutable std::array<long, 3> grid_n = {0, 0, 0};
  double tie_tolerance = 0.0;             // hits closer than this along a ray are one crossing
  std::unique_ptr<PointTree> vertex_tree;  // the vertices, for near()
  std::shared_ptr<const BodyTopology> topology;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  // Embree calls `callback` with `data` for each triangle whose bounds meet the
  // ball of radius max_distance about p (a little larger: float rounding).
  void point_query(const Vec3& p, double max_distance, RTCPointQueryFunction callback, void* data) const {
    RTCPointQuery q;
    q.x = static_cast<float>(p.x());
    q.y = static_cast<float>(p.y());
    q.z = static_cast<float>(p.z());
    q.time = 0.0f;
    q.radius = std::isfinite(max_distance) ? static_cast<float>(max_distance * (1.0 + 1e-6)) + 1e-30f
                                           : std::numeric_limits<float>::infinity();
    RTCPointQueryContext ctx;
    rtcInitPointQueryContext(&ctx);
    rtcPointQuery(scene, &q, &ctx, callback, data);
  }

  PointQueryData query(const Vec3& p, double max_distance) const {
    PointQueryData d{&corners, &degenerate, p};
    point_query(p, max_distance, point_query_callback, &d);
    if (d.best_d2 > max_distance * max_distance) d.best_d2 = kInf;
    return d;
  }

  // Inside decision from the closest feature (Baerentzen and Aanaes' angle-weighted
  // pseudonormal): exact in double for a closed, manifold, oriented mesh.
  // Returns -1 when the feature cannot decide (non-manifold or unoriented).
  int inside_by_pseudonormal(const PointQueryData& d) const {
    if (!topology->oriented || !std::isfinite(d.best_d2)) return -1;
    Vec3 n;
    if (d.region == kFace) {
      n = row3(face_normal, d.tri);
    } else if (d.region >= kEdge0) {
      const Index e = 3 * d.tri + static_cast<Index>(d.region - kEdge0);
      if (!topology->edge_ok[e]) return -1;
      n = row3(edge_normal, e);
    } else {
      const Index v = triangles[d.tri][static_cast<std::size_t>(d.region - kVertex0)];
      if (!topology->vertex_ok[v]) return -1;
      n = row3(vertex_normal, v);
    }
    const double s = (d.p - d.point).dot(n) * orientation;
    return s < 0.0 ? 1 : 0;
  }

  // Crossing count along one ray: hits within tie_tolerance of each other are one
  // crossing place (a shared edge or vertex); its net side (+1, 0 or -1) is what
  // counts, so a ray grazing a silhouette edge adds nothing. Returns the winding
  // number (oriented bodies) or the parity (others); -1 when the ray is unusable.
  int ray_vote(const Vec3& p, const Vec3& dir) const {
    CollectContext c;
    rtcInitIntersectContext(&c.ctx);
    c.ctx.filter = collect_filter;
    c.face_normal = &face_normal;
    c.dir = dir;
    RTCRayHit rh = make_ray(p, dir);
    rtcIntersect1(scene, &c.ctx, &rh);
    if (c.overflow) return -1;
    std::sort(c.hits.begin(), c.hits.begin() + c.count, [](const RayHit& a, const RayHit& b) {
      return a.t < b.t || (a.t == b.t && a.tri < b.tri);
    });
    int winding = 0, crossings = 0;
    for (int i = 0; i < c.count;) {
      int j = i, net = 0;
      Index last_tri = RTC_INVALID_GEOMETRY_ID;
      while (j < c.count && c.hits[static_cast<std::size_t>(j)].t - c.hits[static_cast<std::size_t>(i)].t <=
                                static_cast<float>(tie_tolerance)) {
        const RayHit& h = c.hits[static_cast<std::size_t>(j)];
        if (h.tri != last_tri) net += h.side;  // a triangle reported twice counts once
        last_tri = h.tri;
        ++j;
      }
      const int side = net > 0 ? 1 : (net < 0 ? -1 : 0);
      winding += side;
      crossings += side != 0 ? 1 : 0;
      i = j;
    }
    if (topology->oriented) return winding * static_cast<int>(orientation) > 0 ? 1 : 0;
    return crossings & 1;
  }

  bool inside_by_rays(const Vec3& p) const {
    int yes = 0, no = 0;
    for (const Vec3& dir : ray_directions()) {
      const int v = ray_vote(p, dir);
      if (v == 1) ++yes;
      if (v == 0) ++no;
      if (yes >= 3 || no >= 3) break;  // majority of five reached
    }
    return yes > no;
  }

  long cell_index(long x, long y, long z) const { return (z * grid_n[1] + y) * grid_n[0] + x; }

  void build_grid() const {
    // About half the near tolerance per cell, so a point in a boundary cell is
    // usually within the tolerance and decided by the pseudonormal; capped at
    // about 4M cells.
    const Vec3 ext = hi - lo;
    grid_h = std::max(0.5 * near_tolerance, std::cbrt(ext.prod() / 4.0e6));
    grid_lo = lo - Vec3::Constant(2.0 * grid_h);
    for (int k = 0; k < 3; ++k) grid_n[static_cast<std::size_t>(k)] = static_cast<long>(std::ceil(ext[k] / grid_h)) + 4;
    grid.assign(static_cast<std::size_t>(grid_n[0] * grid_n[1] * grid_n[2]), 255);
    auto cell_of = [&](double v, int k) {
      return std::clamp(static_cast<long>(std::floor((v - grid_lo[k]) / grid_h)), 0L, grid_n[static_cast<std::size_t>(k)] - 1);
    };
    const double pad = 1e-9 * (hi - lo).norm();
    for (const auto& tri : triangles) {
      Vec3 tlo = row3(vertices, tri[0]), thi = tlo;
      for (int k = 1; k < 3; ++k) {
        tlo = tlo.cwiseMin(row3(vertices, tri[static_cast<std::size_t>(k)]));
        thi = thi.cwiseMax(row3(vertices, tri[static_cast<std::size_t>(k)]));
      }
      for (long z = cell_of(tlo.z() - pad, 2); z <= cell_of(thi.z() + pad, 2); ++z)
        for (long y = cell_of(tlo.y() - pad, 1); y <= cell_of(thi.y() + pad, 1); ++y)
          for (long x = cell_of(tlo.x() - pad, 0); x <= cell_of(thi.x() + pad, 0); ++x)
            grid[static_cast<std::size_t>(cell_index(x, y, z))] = kBoundary;
    }
    // Label each region of free cells (6-connected); a region touches no
    // triangle, so one vote at any of its cells is the answer for all of them.
    // In fixed slabs of z, in parallel: a region cut by slab borders gets one
    // vote per piece (the same answer), and the labels do not depend on the
    // thread count. Isolated: this runs inside call_once, often from a parallel
    // loop; a thread waiting here must not pick up that loop's tasks (they would
    // enter call_once again and deadlock).
    // The free cells of a row (along x) come in a few runs between boundary
    // cells: the regions are the runs joined where they overlap a run of the
    // row before in y or in z (a cell-by-cell fill visited each of the 4M cells
    // about six times: a fifth of a small garment's resize a body). Each region
    // votes at its first cell in index order, the first cell of its first run.
    constexpr long kSlabs = 16;
    const long plane = grid_n[0] * grid_n[1];
    const long nx = grid_n[0], ny = grid_n[1];
    struct Run {
      long row;    // index of the row's cell x = 0
      long x0, x1;  // free cells x0 .. x1 - 1
    };
    auto fill_slab = [&](long slab, std::vector<Run>& runs, std::vector<Index>& parent, std::vector<std::size_t>& row_runs) {
      const long z0 = grid_n[2] * slab / kSlabs, z1 = grid_n[2] * (slab + 1) / kSlabs;
      const long rows = (z1 - z0) * ny;
      runs.clear();
      row_runs.assign(static_cast<std::size_t>(rows + 1), 0);
      for (long r = 0; r < rows; ++r) {
        const long row = z0 * plane + r * nx;
        const std::uint8_t* cell = grid.data() + row;
        for (long x = 0; x < nx;) {
          if (cell[x] != 255) {
            ++x;
            continue;
          }
          const long x0 = x;
          while (x < nx && cell[x] == 255) ++x;
          runs.push_back({row, x0, x});
        }
        row_runs[static_cast<std::size_t>(r + 1)] = runs.size();
      }
      parent.resize(runs.size());
      for (std::size_t i = 0; i < runs.size(); ++i) parent[i] = Index(i);
      // Runs of row r joined with the overlapping runs of row `other` (a sweep in x).
      const auto join_rows = [&](long r, long other) {
        std::size_t a = row_runs[static_cast<std::size_t>(r)], b = row_runs[static_cast<std::size_t>(other)];
        const std::size_t a_end = row_runs[static_cast<std::size_t>(r + 1)], b_end = row_runs[static_cast<std::size_t>(other + 1)];
        while (a < a_end && b < b_end) {
          if (runs[a].x0 < runs[b].x1 && runs[b].x0 < runs[a].x1) unite_roots(parent, Index(a), Index(b));
          if (runs[a].x1 < runs[b].x1) ++a;
          else ++b;
        }
      };
      for (long r = 0; r < rows; ++r) {
        if (r % ny > 0) join_rows(r, r - 1);    // y - 1
        if (r >= ny) join_rows(r, r - ny);      // z - 1, within the slab
      }
      // Roots are their region's first run (unite_roots keeps the smaller).
      std::vector<std::uint8_t> label(runs.size(), 0);
      for (std::size_t i = 0; i < runs.size(); ++i) {
        const Index root = find_root(parent, Index(i));
        if (root == Index(i)) {
          const long first = runs[i].row + runs[i].x0;
          const long sx = first % nx, sy = (first / nx) % ny, sz = first / plane;
          const Vec3 centre = grid_lo + grid_h * Vec3(sx + 0.5, sy + 0.5, sz + 0.5);
          label[i] = inside_by_rays(centre) ? kInside : kOutside;
        }
        std::fill(grid.begin() + runs[i].row + runs[i].x0, grid.begin() + runs[i].row + runs[i].x1, label[root]);
      }
    };
    tbb::this_task_arena::isolate([&] {
      parallel_for(0, kSlabs, 1, [&](std::size_t b, std::size_t e) {
        std::vector<Run> runs;
        std::vector<Index> parent;
        std::vector<std::size_t> row_runs;
        for (std::size_t slab = b; slab < e; ++slab) fill_slab(long(slab), runs, parent, row_runs);
      });
    });
  }

  // kInside / kOutside when the grid knows, kBoundary when the point needs a query.
  void ensure_grid() const {
    std::call_once(grid_once, [this] { build_grid(); });
  }

  std::uint8_t grid_label(const Vec3& p) const {
    ensure_grid();
    long c[3];
    for (int k = 0; k < 3; ++k) {
      const double f = std::floor((p[k] - grid_lo[k]) / grid_h);
      if (f < 0.0 || f >= static_cast<double>(grid_n[static_cast<std::size_t>(k)])) return kOutside;  // beyond the box
      c[k] = static_cast<long>(f);
    }
    return grid[static_cast<std::size_t>(cell_index(c[0], c[1], c[2]))];
  }

  bool inside_given(const PointQueryData& d) const {
    if (d.best_d2 == 0.0) return false;  // on the surface is not inside
    if (d.best_d2 <= near_tolerance * near_tolerance) {
      const int s = inside_by_pseudonormal(d);
      if (s >= 0) return s == 1;
    }
    const std::uint8_t g = grid_label(d.p);
    if (g != kBoundary) return g == kInside;
    return inside_by_rays(d.p);
  }
};

BodySurface::BodySurface(const BodyMesh& body, std::shared_ptr<const BodyTopology> topology)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const std::string file = body.path.empty() ? (body.name.empty() ? std::string("<body>") : body.name) : body.path;
  const Index nv = static_cast<Index>(body.vertices.rows());
  const Index nt = static_cast<Index>(body.triangles.size());
  if (nt == 0) throw input_error(file, "body has no triangles");
  if (!body.vertices.allFinite()) throw input_error(file, "body has a NaN or infinite vertex");
  for (Index t = 0; t < nt; ++t)
    for (Index c : body.triangles[t])
      if (c >= nv)
        throw input_error(file, "triangle " + std::to_string(t + 1) + " uses vertex " + std::to_string(c + 1) +
                                    " but the body has " + std::to_string(nv) + " vertices");
  m.vertices = body.vertices;
  m.triangles = body.triangles;
  m.vertex_tree = std::make_unique<PointTree>(m.vertices);
  const bool same = topology && topology->vertex_count == nv && topology->triangles == m.triangles;
  m.topology = same ? std::move(topology) : make_topology(m.triangles, nv);

  // Face normals, degenerate triangles, bounding box, signed volume.
  m.face_normal.setZero(nt, 3);
  m.degenerate.assign(nt, 0);
  m.corners.resize(std::size_t(nt));
  double volume = 0.0;
  for (Index t = 0; t < nt; ++t) {
    const auto& tri = m.triangles[t];
    const Vec3 a = row3(m.vertices, tri[0]), b = row3(m.vertices, tri[1]), c = row3(m.vertices, tri[2]);
    m.corners[std::size_t(t)] = {a, b, c};
    const Vec3 n = (b - a).cross(c - a);
    const double len = n.norm();
    const double scale2 = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()});
    if (!(len > 1e-14 * scale2)) {
      m.degenerate[t] = 1;
    } else {
      m.face_normal.row(t) = (n / len).transpose();
    }
    volume += a.dot(b.cross(c)) / 6.0;
  }
  m.lo = m.vertices.colwise().minCoeff().transpose();
  m.hi = m.vertices.colwise().maxCoeff().transpose();
  const double diag = std::max((m.hi - m.lo).norm(), 1e-300);
  // Within 0.5% of the body's size (about 1 cm on an adult) the closest
  // feature's pseudonormal decides inside; farther out the grid or the rays do,
  // which also stay right where the body intersects itself.
  m.near_tolerance = 5e-3 * diag;
  m.tie_tolerance = 1e-6 * diag;

  // Per edge, the sum of the normals of the faces on it.
  m.edge_normal.setZero(3 * static_cast<Eigen::Index>(nt), 3);
  const BodyTopology& topo = *m.topology;
  for (std::size_t g = 0; g + 1 < topo.edge_start.size(); ++g) {
    Vec3 n = Vec3::Zero();
    for (std::size_t e = topo.edge_start[g]; e < topo.edge_start[g + 1]; ++e) n += row3(m.face_normal, topo.edge_slot[e] / 3);
    for (std::size_t e = topo.edge_start[g]; e < topo.edge_start[g + 1]; ++e) m.edge_normal.row(topo.edge_slot[e]) = n.transpose();
  }
  m.orientation = volume < 0.0 ? -1.0 : 1.0;

  // Angle-weighted vertex pseudonormals.
  m.vertex_normal.setZero(nv, 3);
  for (Index t = 0; t < nt; ++t) {
    if (m.degenerate[t]) continue;
    const auto& tri = m.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = row3(m.vertices, tri[k]);
      const Vec3 e1 = (row3(m.vertices, tri[(k + 1) % 3]) - p).normalized();
      const Vec3 e2 = (row3(m.vertices, tri[(k + 2) % 3]) - p).normalized();
      const double angle = std::acos(std::clamp(e1.dot(e2), -1.0, 1.0));
      m.vertex_normal.row(tri[k]) += angle * m.face_normal.row(t);
    }
  }

  m.device = rtcNewDevice(nullptr);
  if (!m.device) throw Error("Embree: cannot create a device");
  m.scene = rtcNewScene(m.device);
  rtcSetSceneFlags(m.scene, static_cast<RTCSceneFlags>(RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION));
  rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_MEDIUM);
  add_triangles(m.device, m.scene, m.vertices, m.triangles, file);
  commit_scene(m.device, m.scene, file);
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  return closest_on_triangle(p, a, b, c).point;
}

std::shared_ptr<const BodyTopology> body_topology(const BodyMesh& body) {
  const Index nv = static_cast<Index>(body.vertices.rows());
  for (const auto& t : body.triangles)
    for (Index c : t)
      if (c >= nv) throw Error("body topology: a triangle uses vertex " + std::to_string(c + 1) + " of " + std::to_string(nv));
  return make_topology(body.triangles, nv);
}

BodySurface::~BodySurface() = default;
std::shared_ptr<const BodyTopology> BodySurface::topology() const { return impl_->topology; }
BodySurface::BodySurface(BodySurface&&) noexcept = default;
BodySurface& BodySurface::operator=(BodySurface&&) noexcept = default;

ClosestPoint BodySurface::closest(const Vec3& p) const { return closest_within(p, kInf); }

namespace {
// How far p is known to be outside, given that it is and the query `d` that
// searched as far as `searched`: its distance, or the radius when it found nothing.
double known_clear(const PointQueryData& d, double searched) {
  if (!(d.best_d2 > 0.0)) return 0.0;
  return std::isfinite(d.best_d2) ? std::sqrt(d.best_d2) : searched;
}

ClosestPoint closest_of(const PointQueryData& d, const Points& face_normal) {
  ClosestPoint r;
  if (!std::isfinite(d.best_d2)) {
    r.distance = kInf;
    return r;
  }
  r.point = d.point;
  r.normal = row3(face_normal, d.tri);
  r.distance = std::sqrt(d.best_d2);
  r.triangle = d.tri;
  return r;
}
}  // namespace

ClosestPoint BodySurface::closest_within(const Vec3& p, double max_distance) const {
  return closest_of(impl_->query(p, max_distance), impl_->face_normal);
}

bool BodySurface::closer_than(const Vec3& p, double max_distance) const {
  Index hint = kNoHint;
  return closer_than(p, max_distance, hint);
}

bool BodySurface::closer_than(const Vec3& p, double max_distance, Index& hint) const {
  if (!p.allFinite() || !(max_distance > 0.0)) return false;
  CloserThanData d{{&impl_->corners, &impl_->degenerate, p}, max_distance};
  if (hint < impl_->triangles.size() && closer_than_test(d, hint)) return true;
  impl_->point_query(p, max_distance, closer_than_callback, &d);
  if (d.found) hint = d.tri;
  return d.found;
}

SignedClosestPoint BodySurface::signed_closest_within(const Vec3& p, double max_distance) const {
  SignedClosestPoint r;
  if (!p.allFinite()) {
    r.distance = kInf;
    return r;
  }
  const PointQueryData d = impl_->query(p, max_distance);
  static_cast<ClosestPoint&>(r) = closest_of(d, impl_->face_normal);
  if (std::isfinite(d.best_d2)) r.inside = impl_->inside_given(d);
  return r;
}

void BodySurface::prepare_inside_test() const { impl_->ensure_grid(); }

bool BodySurface::inside(const Vec3& p) const { return inside_or_clear(p).inside; }

SignedClosestPoint BodySurface::inside_or_clear(const Vec3& p) const {
  SignedClosestPoint r;
  if (!p.allFinite()) return r;
  const std::uint8_t g = impl_->grid_label(p);
  if (g != Impl::kBoundary) {
    r.inside = g == Impl::kInside;
    return r;
  }
  // Only a nearby closest point is needed: farther points go to the rays anyway.
  const PointQueryData d = impl_->query(p, impl_->near_tolerance);
  r.inside = impl_->inside_given(d);
  if (!r.inside) r.clear = known_clear(d, impl_->near_tolerance);
  return r;
}

SignedClosestPoint BodySurface::closest_and_inside(const Vec3& p, double max_distance) const {
  SignedClosestPoint r;
  if (!p.allFinite()) {
    r.distance = kInf;
    return r;
  }
  const std::uint8_t g = impl_->grid_label(p);
  if (g == Impl::kInside) {
    static_cast<ClosestPoint&>(r) = closest(p);
    r.inside = true;
    return r;
  }
  if (g == Impl::kOutside) {
    static_cast<ClosestPoint&>(r) = closest_within(p, max_distance);
    r.clear = std::min(r.distance, max_distance);
    return r;
  }
  // inside() queries as far as near_tolerance; one query as far as both need
  // finds the same closest point (ties go to the lowest triangle either way).
  const double searched = std::max(max_distance, impl_->near_tolerance);
  PointQueryData d = impl_->query(p, searched);
  PointQueryData near = d;
  if (near.best_d2 > impl_->near_tolerance * impl_->near_tolerance) near.best_d2 = kInf;
  r.inside = impl_->inside_given(near);
  if (!r.inside) r.clear = known_clear(d, searched);
  if (r.inside && !std::isfinite(d.best_d2)) d = impl_->query(p, kInf);
  if (!r.inside && d.best_d2 > max_distance * max_distance) d.best_d2 = kInf;
  static_cast<ClosestPoint&>(r) = closest_of(d, impl_->face_normal);
  return r;
}

void BodySurface::near(const Vec3& p, double radius, Near& out) const {
  out.points.clear();
  out.within = 0;
  out.edges.clear();
  if (!(radius > 0.0)) return;
  const Impl& m = *impl_;
  thread_local std::vector<std::pair<Index, double>> found;
  m.vertex_tree->within(p, radius * radius, found);
  // Per body vertex, its row of out.points (kNone: none), for the ends of the
  // edges: a face's call asks it of every neighbour of some 30 vertices. Kept
  // between calls (a body's worth of rows), the marked rows cleared on return.
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  thread_local std::vector<std::uint32_t> row_of;
  thread_local std::vector<Index> marked;
  if (row_of.size() < std::size_t(m.vertices.rows())) row_of.resize(std::size_t(m.vertices.rows()), kNone);
  struct Unmark {
    ~Unmark() {
      for (const Index v : marked) row_of[v] = kNone;
      marked.clear();
    }
  } unmark;
  const auto add = [&](Index v) {
    row_of[v] = std::uint32_t(out.points.size());
    marked.push_back(v);
    out.points.push_back(row3(m.vertices, v));
  };
  for (const auto& [v, d2] : found) add(v);
  out.within = out.points.size();
  thread_local std::vector<Index> in;
  in.assign(marked.begin(), marked.end());
  std::sort(in.begin(), in.end());
  for (const Index v : in)
    for (const Index w : m.topology->neighbours.row(v)) {  // once: from its smaller end, or from its only end within
      if (!(v < w || !(row_of[w] < out.within))) continue;
      if (row_of[w] == kNone) add(w);  // an end outside the radius, once
      out.edges.push_back({row_of[v], row_of[w]});
    }
}

double BodySurface::signed_distance(const Vec3& p) const {
  if (!p.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const PointQueryData d = impl_->query(p, kInf);
  const double dist = std::sqrt(d.best_d2);
  return impl_->inside_given(d) ? -dist : dist;
}

double BodySurface::intersect(const Vec3& origin, const Vec3& dir, Index* tri_out) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh = make_ray(origin, dir);
  rtcIntersect1(impl_->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return kInf;
  if (tri_out) *tri_out = rh.hit.primID;
  return static_cast<double>(rh.ray.tfar);
}

}  // namespace refit
