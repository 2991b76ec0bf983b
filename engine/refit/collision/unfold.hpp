#pragma once
// No folds, for the collision step (collision.cpp): a correction
// (a displacement per region vertex) that would turn a face over is evened out
// over that face's corners until no face turns.
#include <refit/core/garment.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace refit {

// A set of vertices this small against the garment's `total` has its faces
// listed from the vertices (faces_around) rather than found by a scan of every face.
inline bool few_vertices(std::size_t count, std::size_t total) { return count * 16 <= total; }

// Newell normal of face f with its region corners displaced by disp.
template <class SlotOf>
Vec3 displaced_face_normal(const Garment& g, const Points& positions, std::size_t f, const SlotOf& slot_of,
                 const std::vector<Vec3>* disp) {
  const auto face = g.faces.row(f);
  Vec3 n = Vec3::Zero();
  auto at = [&](Index v) {
    Vec3 p = row3(positions, v);
    if (disp) {
      const long k = slot_of(v);
      if (k >= 0) p += (*disp)[std::size_t(k)];
    }
    return p;
  };
  for (std::size_t i = 0; i < face.size(); ++i) n += at(face[i]).cross(at(face[(i + 1) % face.size()]));
  return n;
}

// No folds: a face the correction would turn over (its normal against the one
// it had) gets each corner's displacement replaced by the mean over its
// turned-over faces of their corners' mean displacement (a face whose corners
// all move alike keeps its normal), for up to `passes` passes. Faces the
// correction does not reach (no region corner) cannot turn. After the first
// pass only the faces around a changed corner are tested again: the others
// keep their verdict. `faces_of_vertex()`: vertex_faces(g), asked for a small region only.
template <class FacesOfVertex, class SlotOf>
void unfold(const Garment& g, const Points& positions, const std::vector<Index>& region,
            const FacesOfVertex& faces_of_vertex, const SlotOf& slot_of, int passes, std::vector<Vec3>& disp) {
  // Faces with a corner in the region, ascending: a small region's own (a
  // repair round's tens of vertices of the 1M dress: the scan took 3.5 ms),
  // else from a scan in blocks, each listing its own, joined in order.
  const std::size_t nf = g.faces.rows();
  std::vector<Index> faces;
  if (few_vertices(region.size(), std::size_t(positions.rows()))) {
    for (Index f : faces_around(faces_of_vertex(), region))
      if (g.faces.row_size(f) >= 3) faces.push_back(f);
  } else {
    faces = gather_in_blocks<Index>(nf, 4096, [&](std::size_t first, std::size_t last, std::vector<Index>& out) {
      for (std::size_t f = first; f < last; ++f) {
        const auto face = g.faces.row(f);
        if (face.size() >= 3 && std::any_of(face.begin(), face.end(), [&](Index v) { return slot_of(v) >= 0; }))
          out.push_back(Index(f));
      }
    });
  }
  std::vector<Vec3> before(faces.size());
  parallel_for(0, faces.size(), 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) before[i] = displaced_face_normal(g, positions, faces[i], slot_of, nullptr);
  });
  // Per region slot, the positions in `faces` of its faces (CSR).
  std::vector<std::size_t> start(region.size() + 1, 0);
  for (Index f : faces)
    for (Index v : g.faces.row(f))
      if (slot_of(v) >= 0) ++start[std::size_t(slot_of(v)) + 1];
  for (std::size_t k = 0; k < region.size(); ++k) start[k + 1] += start[k];
  std::vector<std::size_t> face_at(start.back()), fill(start.begin(), start.end() - 1);
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (Index v : g.faces.row(faces[i]))
      if (slot_of(v) >= 0) face_at[fill[std::size_t(slot_of(v))]++] = i;

  std::vector<std::uint8_t> turned(faces.size(), 0), dirty(faces.size(), 0);
  std::vector<std::size_t> test(faces.size());  // the faces to test this pass, ascending
  for (std::size_t i = 0; i < faces.size(); ++i) test[i] = i;
  // The turned faces, ascending: a face keeps its verdict until it is tested
  // again, so each pass merges the tested faces' new verdicts into the list
  // instead of reading every face (the 1M dress's first round: 625k faces, 10 passes).
  std::vector<std::size_t> turned_list, merged;
  // Per region slot, the sum and count of its turned faces' mean displacements;
  // zeroed again after each pass where they were used.
  std::vector<Vec3> sum(region.size(), Vec3::Zero());
  std::vector<int> count(region.size(), 0);
  std::vector<std::size_t> used;  // slots with count > 0 this pass
  for (int pass = 0; pass < passes; ++pass) {
    parallel_for(0, test.size(), 256, [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        const std::size_t i = test[t];
        turned[i] = before[i].squaredNorm() > 0.0 && displaced_face_normal(g, positions, faces[i], slot_of, &disp).dot(before[i]) <= 0.0;
      }
    });
    merged.clear();
    for (std::size_t a = 0, t = 0; a < turned_list.size() || t < test.size();) {
      if (t == test.size() || (a < turned_list.size() && turned_list[a] < test[t])) {
        merged.push_back(turned_list[a++]);  // not tested again: still turned
      } else {
        if (a < turned_list.size() && turned_list[a] == test[t]) ++a;
        if (turned[test[t]]) merged.push_back(test[t]);
        ++t;
      }
    }
    std::swap(turned_list, merged);
    if (turned_list.empty()) return;
    used.clear();
    for (std::size_t i : turned_list) {  // in face order: the sums are the same for any thread count
      const auto face = g.faces.row(faces[i]);
      Vec3 mean = Vec3::Zero();
      for (Index v : face) {
        const long k = slot_of(v);
        if (k >= 0) mean += disp[std::size_t(k)];
      }
      mean /= double(face.size());
      for (Index v : face) {
        const long k = slot_of(v);
        if (k < 0) continue;
        if (count[std::size_t(k)]++ == 0) used.push_back(std::size_t(k));
        sum[std::size_t(k)] += mean;
      }
    }
    test.clear();
    for (std::size_t k : used) {
      const Vec3 d = sum[k] / double(count[k]);
      sum[k] = Vec3::Zero();
      count[k] = 0;
      if (d == disp[k]) continue;
      disp[k] = d;
      for (std::size_t a = start[k]; a < start[k + 1]; ++a)
        if (!dirty[face_at[a]]) dirty[face_at[a]] = 1, test.push_back(face_at[a]);
    }
    if (test.empty()) return;  // nothing changed: the passes left would change nothing either
    std::sort(test.begin(), test.end());
    for (std::size_t i : test) dirty[i] = 0;
  }
}

}  // namespace refit
