#include <refit/collision/collision.hpp>
#include <refit/core/topology.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include <algorithm>
#include <cmath>

namespace refit {

namespace {

constexpr std::size_t kGrain = 4096;

// What a too-close vertex needs: its displacement along unit `dir` must reach `amount`.
struct Constraint {
  Vec3 dir = Vec3::Zero();
  double amount = 0.0;
  bool active = false;
  bool inside = false;
};

Constraint check_vertex(const Vec3& p, const BodySurface& body, double clearance) {
  Constraint c;
  const bool in = body.inside(p);
  const ClosestPoint cp = in ? body.closest(p) : body.closest_within(p, clearance);
  if (!in && !(cp.distance < clearance)) return c;
  c.active = true;
  c.inside = in;
  const Vec3 towards = cp.point - p;
  const double len = towards.norm();
  // The closest-point direction is the body's normal there (face, edge or vertex
  // normal alike); on the surface itself only the face normal is left.
  if (len > 1e-12 * (1.0 + p.norm())) {
    c.dir = in ? Vec3(towards / len) : Vec3(-towards / len);
  } else {
    c.dir = cp.normal;
  }
  c.amount = in ? len + clearance : clearance - len;
  return c;
}

// Corner mean of face f.
Vec3 face_centre(const Garment& g, const Points& positions, std::size_t f) {
  Vec3 centre = Vec3::Zero();
  for (Index v : g.faces.row(f)) centre += row3(positions, v);
  return centre / double(g.faces.row_size(f));
}

bool face_centre_inside(const Garment& g, const Points& positions, std::size_t f, const BodySurface& body) {
  if (g.faces.row_size(f) < 3) return false;
  const Vec3 centre = face_centre(g, positions, f);
  return centre.allFinite() && body.inside(centre);
}

}  // namespace


CollisionReport resolve_penetrations(const Garment& g, Points& positions, const BodySurface& body_b,
                                     const CollisionOptions& options) {
  if (positions.rows() != g.positions.rows())
    throw Error("penetration resolution: " + std::to_string(positions.rows()) + " positions for a garment of " +
                std::to_string(g.positions.rows()) + " vertices");
  if (!(options.clearance >= 0.0)) throw Error("penetration resolution: the clearance must be >= 0");
  const std::size_t n = static_cast<std::size_t>(positions.rows());
  CollisionReport report;
  std::vector<Index> to_check;  // empty in round 1: check everything
  std::vector<Index> touched;   // every vertex any round may have moved
  std::vector<int> ring(n, -1);
  std::vector<std::uint8_t> finite(n, 0);
  parallel_for(0, n, kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) finite[i] = positions.row(static_cast<Eigen::Index>(i)).allFinite() ? 1 : 0;
  });
  report.checked = deterministic_sum<std::size_t>(0, n, kGrain, 0, [&](std::size_t i) { return finite[i]; });
  std::vector<std::uint8_t> is_touched(n, 0);
  std::vector<std::uint8_t> face_inside_before;  // per face: its centre inside body B before
  std::vector<Vec3> first_position;  // aligned with `touched`: where each started

  // The inside test's grid, built in parallel here rather than on the first
  // inside() call of the parallel loop below (there it would run on one thread).
  body_b.prepare_inside_test();
  const Csr adj = vertex_adjacency(g);

  for (int round = 0; round < std::max(1, options.max_rounds); ++round) {
    // 1. Which vertices are inside or too close, and where they must go: fixed
    // blocks, each listing its constrained vertices, joined in block order.
    const std::size_t count = round == 0 ? n : to_check.size();
    constexpr std::size_t kBlock = kGrain / 4;
    std::vector<std::vector<std::pair<Index, Constraint>>> found((count + kBlock - 1) / kBlock);
    parallel_for(0, found.size(), 1, [&](std::size_t b, std::size_t e) {
      for (std::size_t blk = b; blk < e; ++blk)
        for (std::size_t k = blk * kBlock; k < std::min(count, (blk + 1) * kBlock); ++k) {
          const Index i = round == 0 ? static_cast<Index>(k) : to_check[k];
          if (!finite[i]) continue;
          const Constraint c = check_vertex(row3(positions, i), body_b, options.clearance);
          if (c.active) found[blk].emplace_back(i, c);
        }
    });
    // Faces too: a coarse face whose corners all clear the body can still have
    // the body poking through its middle (the real dress's bust: 115 face centres
    // inside body B, none of its corners). A face whose centre is inside or too
    // close gives each corner its centre's constraint (moving all corners by it
    // moves the centre by it); a corner with several keeps the largest.
    std::vector<std::uint8_t> check_face_of(round == 0 ? 0 : n, 0);
    if (round == 0) face_inside_before.assign(g.faces.rows(), 0);
    for (std::size_t k = 0; round > 0 && k < count; ++k) check_face_of[to_check[k]] = 1;
    const std::size_t nf = g.faces.rows();
    std::vector<std::vector<std::pair<Index, Constraint>>> face_found((nf + kBlock - 1) / kBlock);
    std::vector<std::size_t> faces_in(face_found.size(), 0);
    parallel_for(0, face_found.size(), 1, [&](std::size_t b, std::size_t e) {
      for (std::size_t blk = b; blk < e; ++blk)
        for (std::size_t f = blk * kBlock; f < std::min(nf, (blk + 1) * kBlock); ++f) {
          const auto face = g.faces.row(f);
          if (face.size() < 3) continue;
          bool check = round == 0, ok = true;
          for (Index v : face) {
            check = check || check_face_of[v];
            ok = ok && finite[v];
          }
          if (!check || !ok) continue;
          const Constraint c = check_vertex(face_centre(g, positions, f), body_b, options.clearance);
          if (!c.active) continue;
          faces_in[blk] += c.inside;
          if (round == 0) face_inside_before[f] = c.inside;
          for (Index v : face) face_found[blk].emplace_back(v, c);
        }
    });
    std::vector<std::pair<Index, Constraint>> by_vertex;
    for (const auto& list : found) by_vertex.insert(by_vertex.end(), list.begin(), list.end());
    const std::size_t vertex_constraints = by_vertex.size();
    for (const auto& list : face_found) by_vertex.insert(by_vertex.end(), list.begin(), list.end());
    // By vertex, in a fixed order (the vertex's own first, then faces in order), largest amount kept.
    std::stable_sort(by_vertex.begin(), by_vertex.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    std::vector<Index> active;  // ascending
    std::vector<Constraint> con;  // aligned with `active`
    for (const auto& [i, c] : by_vertex) {
      if (!active.empty() && active.back() == i) {
        if (c.amount > con.back().amount) con.back() = Constraint{c.dir, c.amount, true, con.back().inside};
        continue;
      }
      active.push_back(i);
      con.push_back(c);
    }
    if (round == 0) {
      report.too_close = vertex_constraints;
      for (const auto& list : found)
        for (const auto& ic : list) report.inside_before += ic.second.inside ? 1 : 0;
      for (std::size_t k : faces_in) report.face_centres_inside_before += k;
    }
    if (active.empty()) break;
    report.rounds = round + 1;

    // 2. The region a correction may spread over: up to smoothing_rings edges away.
    std::vector<Index> region = active;
    for (Index i : active) ring[i] = 0;
    for (std::size_t head = 0, level_end = region.size(), level = 0;
         head < region.size() && static_cast<int>(level) < options.smoothing_rings; ++level) {
      for (; head < level_end; ++head)
        for (Index j : adj.row(region[head]))
          if (ring[j] < 0 && finite[j]) {
            ring[j] = static_cast<int>(level) + 1;
            region.push_back(j);
          }
      level_end = region.size();
    }
    std::sort(region.begin(), region.end());  // mesh order: deterministic and cache-friendly
    for (Index i : region)
      if (!is_touched[i]) {
        is_touched[i] = 1;
        touched.push_back(i);
        first_position.push_back(row3(positions, i));
      }

    // 3. Jacobi smoothing of the displacement field; constrained vertices keep
    // at least their required displacement along their direction. Vertices out of
    // the region count as fixed (zero), which gives the correction its falloff.
    const std::size_t m = region.size();
    std::vector<Vec3> disp(m, Vec3::Zero()), next(m);
    auto slot_of = [&](Index v) -> long {
      auto it = std::lower_bound(region.begin(), region.end(), v);
      return (it != region.end() && *it == v) ? static_cast<long>(it - region.begin()) : -1L;
    };
    // Each region vertex's in-region neighbours, as slots of `region`.
    std::vector<std::vector<long>> rows(m);
    parallel_for(0, m, 256, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) {
        for (Index j : adj.row(region[k])) {
          const long s = slot_of(j);
          if (s >= 0) rows[k].push_back(s);
        }
      }
    });
    // The constraint of each region slot, if any (both lists ascending).
    std::vector<const Constraint*> con_at(m, nullptr);
    for (std::size_t k = 0, a = 0; k < m && a < active.size(); ++k)
      if (region[k] == active[a]) con_at[k] = &con[a++];
    auto enforce = [&](std::size_t k, Vec3& d) {
      const Constraint* c = con_at[k];
      if (!c) return;
      const double along = d.dot(c->dir);
      if (along < c->amount) d += (c->amount - along) * c->dir;
    };
    for (std::size_t k = 0; k < m; ++k) enforce(k, disp[k]);
    for (int pass = 0; pass < options.smoothing_passes; ++pass) {
      parallel_for(0, m, 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
          Vec3 sum = disp[k];
          for (long s : rows[k]) sum += disp[static_cast<std::size_t>(s)];
          // Out-of-region neighbours contribute zero but still count.
          const double deg = 1.0 + static_cast<double>(adj.row_size(region[k]));
          next[k] = sum / deg;
          enforce(k, next[k]);
        }
      });
      std::swap(disp, next);
    }
    parallel_for(0, m, 1024, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) positions.row(region[k]) += disp[k].transpose();
    });
    for (Index i : region) ring[i] = -1;
    to_check = std::move(region);
  }
  // Anything still inside after the last round (reported, never hidden).
  if (report.rounds > 0) {
    const std::size_t t = touched.size();
    report.inside_after = deterministic_sum<std::size_t>(0, t, 256, 0, [&](std::size_t k) {
      const Vec3 p = row3(positions, touched[k]);
      return p.allFinite() && body_b.inside(p) ? 1 : 0;
    });
  }
  // Only faces with a moved corner can have changed.
  report.face_centres_inside_after = deterministic_sum<std::size_t>(0, g.faces.rows(), kGrain, 0, [&](std::size_t f) {
    const auto face = g.faces.row(f);
    const bool moved = std::any_of(face.begin(), face.end(), [&](Index v) { return is_touched[v] != 0; });
    return std::size_t{moved ? face_centre_inside(g, positions, f, body_b) : face_inside_before[f] != 0};
  });
  double total = 0.0;
  for (std::size_t k = 0; k < touched.size(); ++k) {
    const double d = (row3(positions, touched[k]) - first_position[k]).norm();
    if (d > 0.0) {
      ++report.moved;
      total += d;
      report.max_displacement = std::max(report.max_displacement, d);
    }
  }
  report.mean_displacement = report.moved ? total / static_cast<double>(report.moved) : 0.0;
  return report;
}

nlohmann::json CollisionReport::to_json() const {
  return {{"checked", checked},
          {"inside_before", inside_before},
          {"too_close", too_close},
          {"moved", moved},
          {"max_displacement", max_displacement},
          {"mean_displacement", mean_displacement},
          {"inside_after", inside_after},
          {"face_centres_inside_before", face_centres_inside_before},
          {"face_centres_inside_after", face_centres_inside_after},
          {"rounds", rounds}};
}

}  // namespace refit
