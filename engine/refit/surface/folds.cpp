#include <refit/surface/folds.hpp>

#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>

#include <algorithm>

namespace refit {

namespace {

constexpr std::size_t kGrain = 4096;
// A face counts as agreeing on the original only within 60 degrees of its
// corners' normals: not at a crease (a collar's, a lapel's), where turning it
// the other way is no fold.
constexpr double kSmoothAround = 0.5;

// Face normals and, per vertex, the sum of its faces' normals (in face order: the same bits for any thread count).
struct Orientation {
  const Garment& g;
  const Csr& faces_of_vertex;
  std::vector<Vec3> face, vertex;

  Orientation(const Garment& garment, const Csr& fov, const Points& positions)
      : g(garment), faces_of_vertex(fov), face(garment.faces.rows()), vertex(positions.rows()) {
    parallel_for(0, face.size(), kGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t f = b; f < e; ++f) face[f] = face_normal(positions, g.faces.row(f));
    });
    parallel_for(0, vertex.size(), kGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v) vertex[v] = sum_at(Index(v));
    });
  }
  Vec3 sum_at(Index v) const {
    Vec3 s = Vec3::Zero();
    for (Index f : faces_of_vertex.row(v)) s += face[f];
    return s;
  }
  // Whether face f's normal is within the angle whose cosine is `cos_min` of the sum of its corners' normals.
  bool agrees(std::size_t f, double cos_min = 0.0) const {
    Vec3 around = Vec3::Zero();
    for (Index v : g.faces.row(f)) around += vertex[v];
    return face[f].squaredNorm() > 0.0 && face[f].dot(around) > cos_min * face[f].norm() * around.norm();
  }
  // After the vertices `moved` moved: their faces' normals and their corners'
  // sums again; returns the faces whose verdict may have changed (in no order),
  // each marked with `stamp` in face_mark. Stamps grow by 2 a call.
  std::vector<Index> update(const Points& positions, const std::vector<Index>& moved, std::uint32_t stamp,
                            std::vector<std::uint32_t>& face_mark, std::vector<std::uint32_t>& vertex_mark) {
    std::vector<Index> turned, corners, retest;
    for (Index v : moved)
      for (Index f : faces_of_vertex.row(v))
        if (face_mark[f] != stamp - 1) face_mark[f] = stamp - 1, turned.push_back(f);
    parallel_for(0, turned.size(), 1024, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) face[turned[i]] = face_normal(positions, g.faces.row(turned[i]));
    });
    for (Index f : turned)
      for (Index v : g.faces.row(f))
        if (vertex_mark[v] != stamp) vertex_mark[v] = stamp, corners.push_back(v);
    parallel_for(0, corners.size(), 1024, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) vertex[corners[i]] = sum_at(corners[i]);
    });
    for (Index v : corners)
      for (Index f : faces_of_vertex.row(v))
        if (face_mark[f] != stamp) face_mark[f] = stamp, retest.push_back(f);
    return retest;
  }
};

}  // namespace

std::vector<std::uint8_t> faces_agreeing(const Garment& g, const Csr& faces_of_vertex, const Points& positions) {
  const Orientation o(g, faces_of_vertex, positions);
  std::vector<std::uint8_t> agrees(g.faces.rows(), 0);
  parallel_for(0, agrees.size(), kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) agrees[f] = o.agrees(f, kSmoothAround);
  });
  return agrees;
}

FoldBinding bind_folds(const Garment& g) {
  FoldBinding b;
  b.faces_of_vertex = vertex_faces(g);
  b.agrees = faces_agreeing(g, b.faces_of_vertex, g.positions);
  return b;
}

FoldReport smooth_out_folds(const Garment& g, const FoldBinding& binding, Points& positions, const Csr& adjacency,
                            const std::vector<std::uint8_t>* pinned, const FoldOptions& options) {
  FoldReport rep;
  const Points& original = g.positions;
  Orientation o(g, binding.faces_of_vertex, positions);
  const std::size_t nf = g.faces.rows();
  std::vector<std::uint8_t> is_folded(nf, 0);
  parallel_for(0, nf, kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) is_folded[f] = binding.agrees[f] && !o.agrees(f);
  });
  std::vector<Index> folded;
  for (std::size_t f = 0; f < nf; ++f)
    if (is_folded[f]) folded.push_back(Index(f));
  rep.folded_before = rep.folded_after = folded.size();
  const std::size_t nv = std::size_t(positions.rows());
  std::vector<std::uint8_t> in(nv, 0), moved(nv, 0);
  std::vector<std::uint32_t> face_mark(nf, 0), vertex_mark(nv, 0);
  std::uint32_t stamp = 0;
  std::vector<Index> region;  // grows round by round: a fold left over widens its region
  while (!folded.empty() && rep.rounds < options.max_rounds) {
    ++rep.rounds;
    std::vector<Index> front;
    for (Index f : folded)
      for (Index v : g.faces.row(f))
        if (!in[v]) in[v] = 1, front.push_back(v), region.push_back(v);
    for (int r = 0; r < options.rings; ++r) {
      std::vector<Index> next;
      for (Index v : front)
        for (Index w : adjacency.row(v))
          if (!in[w]) in[w] = 1, next.push_back(w), region.push_back(w);
      front = std::move(next);
    }
    std::sort(region.begin(), region.end());
    std::vector<Index> free;
    for (Index v : region)
      if (!(pinned && (*pinned)[v]) && adjacency.row_size(v) > 0) free.push_back(v);
    std::vector<Vec3> next(free.size()), kept(free.size());
    for (std::size_t k = 0; k < free.size(); ++k) kept[k] = row3(positions, free[k]);
    for (int pass = 0; pass < options.passes; ++pass) {
      parallel_for(0, free.size(), 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
          Vec3 sum = Vec3::Zero();
          for (Index w : adjacency.row(free[k])) sum += row3(positions, w) - row3(original, w);
          next[k] = row3(original, free[k]) + sum / double(adjacency.row_size(free[k]));
        }
      });
      for (std::size_t k = 0; k < free.size(); ++k) positions.row(free[k]) = next[k].transpose();
    }
    stamp += 2;
    const std::vector<Index> retest = o.update(positions, free, stamp, face_mark, vertex_mark);
    std::vector<std::uint8_t> was(retest.size());
    std::size_t left = folded.size();
    for (std::size_t i = 0; i < retest.size(); ++i) {
      const Index f = retest[i];
      was[i] = is_folded[f];
      is_folded[f] = binding.agrees[f] && !o.agrees(f);
      left = left - was[i] + is_folded[f];
    }
    if (left >= folded.size()) {  // no better: this round is undone
      for (std::size_t k = 0; k < free.size(); ++k) positions.row(free[k]) = kept[k].transpose();
      break;
    }
    for (Index v : free)
      if (!moved[v]) moved[v] = 1, ++rep.smoothed;
    std::vector<Index> now;  // the folds not retested, and the retested ones folded now
    for (Index f : folded)
      if (face_mark[f] != stamp) now.push_back(f);
    for (Index f : retest)
      if (is_folded[f]) now.push_back(f);
    std::sort(now.begin(), now.end());
    folded = std::move(now);
    rep.folded_after = folded.size();
  }
  return rep;
}

}  // namespace refit
