#include <refit/attach/attachment.hpp>

#include <refit/body/body_surface.hpp>
#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

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

std::vector<Candidate> merge_chunks(const std::vector<std::vector<Candidate>>& chunks, std::size_t n) {
  std::vector<Candidate> best(n);
  for (const auto& chunk : chunks)
    for (std::size_t s = 0; s < n; ++s)
      if (chunk[s].d2 < best[s].d2) best[s] = chunk[s];
  return best;
}

constexpr std::size_t kChunk = 1 << 16;

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

SurfaceAttachment attach_points(const Garment& original, const Points& samples) {
  const std::size_t n = static_cast<std::size_t>(samples.rows());
  const std::size_t ne = original.faces.rows() + original.lines.rows() + original.points.rows();
  SurfaceAttachment at;
  at.vertex.resize(n);
  at.weight.resize(n);
  at.offset.resize(samples.rows(), 3);
  if (n == 0) return at;
  if (ne == 0 && original.vertex_count() == 0) throw Error("attaching points: the garment has no vertices");
  const auto sample = [&](std::size_t s) { return Vec3(samples.row(static_cast<Eigen::Index>(s)).transpose()); };
  const Points& x = original.positions;

  // 1. Each element offers its closest point to the samples within its bounding
  // sphere grown by `slack`: linear in the garment, and exact for every sample
  // whose closest element is nearer than `slack` (feature samples lie on the surface).
  const Vec3 lo = samples.colwise().minCoeff().transpose(), hi = samples.colwise().maxCoeff().transpose();
  const double slack = std::max(1e-9, 0.02 * (hi - lo).norm());
  const PointTree tree(samples);
  const std::size_t chunks = (ne + kChunk - 1) / kChunk;
  std::vector<std::vector<Candidate>> per_chunk(chunks, std::vector<Candidate>(n));
  parallel_for(0, chunks, 1, [&](std::size_t cb, std::size_t ce) {
    std::vector<std::pair<Index, double>> near;
    for (std::size_t c = cb; c < ce; ++c)
      for_each_element(original, c * kChunk, std::min(ne, (c + 1) * kChunk), [&](const std::array<Index, 3>& v, int corners) {
        const Vec3 centre = (row3(x, v[0]) + row3(x, v[1]) + row3(x, v[2])) / 3.0;
        double r = 0.0;
        for (Index k : v) r = std::max(r, (row3(x, k) - centre).norm());
        tree.within(centre, (r + slack) * (r + slack), near);
        for (const auto& [s, d2] : near) {
          const Candidate cand = closest_on_element(sample(std::size_t(s)), x, v, corners);
          Candidate& best = per_chunk[c][std::size_t(s)];
          if (cand.d2 < best.d2) best = cand;
        }
      });
  });
  std::vector<Candidate> best = merge_chunks(per_chunk, n);

  // 2. The rare sample farther than `slack` from every element: all elements (or,
  // for a garment of bare vertices, all vertices).
  parallel_for(0, n, 1, [&](std::size_t sb, std::size_t se) {
    for (std::size_t s = sb; s < se; ++s) {
      if (best[s].d2 <= slack * slack) continue;
      const Vec3 p = sample(s);
      for_each_element(original, 0, ne, [&](const std::array<Index, 3>& v, int corners) {
        const Candidate cand = closest_on_element(p, x, v, corners);
        if (cand.d2 < best[s].d2) best[s] = cand;
      });
      if (ne == 0)
        for (Index v = 0; v < Index(original.vertex_count()); ++v) {
          const Candidate cand = closest_on_element(p, x, {v, v, v}, 1);
          if (cand.d2 < best[s].d2) best[s] = cand;
        }
    }
  });
  for (std::size_t s = 0; s < n; ++s) {
    at.vertex[s] = best[s].vertex;
    at.weight[s] = best[s].weight;
    // Keep the sample's small offset from the surface as it was.
    at.offset.row(static_cast<Eigen::Index>(s)) = (sample(s) - best[s].point).transpose();
  }
  return at;
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
