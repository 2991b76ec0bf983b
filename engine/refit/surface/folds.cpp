#include <refit/surface/folds.hpp>

#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <limits>
#include <span>
#include <unordered_map>

namespace refit {

namespace {

constexpr std::size_t kFoldGrain = 4096;
// A face counts as agreeing on the original only within 60 degrees of its
// corners' normals: not at a crease (a collar's, a lapel's), where turning it
// the other way is no fold.
constexpr double kSmoothAround = 0.5;

// The entries of `list` with keep(entry), in order.
template <class Keep>
std::vector<Index> entries_where(std::span<const Index> list, const Keep& keep) {
  return gather_in_blocks<Index>(list.size(), kFoldGrain, [&](std::size_t first, std::size_t last, std::vector<Index>& out) {
    for (std::size_t k = first; k < last; ++k)
      if (keep(list[k])) out.push_back(list[k]);
  });
}

// The neighbours w of the vertices of `from` with take(w), in the order a
// serial walk lists them (from's order, then each vertex's adjacency order),
// repeats kept. `take` only reads: the caller marks what it keeps in a serial
// pass over the list.
template <class Take>
std::vector<Index> neighbours_where(const Csr& adjacency, std::span<const Index> from, const Take& take) {
  return gather_in_blocks<Index>(from.size(), kFoldGrain, [&](std::size_t first, std::size_t last, std::vector<Index>& out) {
    for (std::size_t k = first; k < last; ++k)
      for (Index w : adjacency.row(from[k]))
        if (take(w)) out.push_back(w);
  });
}

// Face normals and, per vertex, the sum of its faces' normals (in face order: the same bits for any thread count).
struct Orientation {
  const Garment& g;
  const Csr& faces_of_vertex;
  std::vector<Vec3> face, vertex;
  // Marks of update(): faces and corners seen this call (stamps grow by 2 a call).
  std::vector<std::uint32_t> face_mark, vertex_mark;
  std::uint32_t stamp = 0;

  Orientation(const Garment& garment, const Csr& fov, const Points& positions)
      : g(garment), faces_of_vertex(fov), face(garment.faces.rows()), vertex(positions.rows()) {
    parallel_for(0, face.size(), kFoldGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t f = b; f < e; ++f) face[f] = face_normal(positions, g.faces.row(f));
    });
    parallel_for(0, vertex.size(), kFoldGrain, [&](std::size_t b, std::size_t e) {
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
  // sums again; returns the faces whose verdict may have changed (ascending),
  // for which retested() is true until the next call.
  std::vector<Index> update(const Points& positions, const std::vector<Index>& moved) {
    if (face_mark.empty()) face_mark.assign(face.size(), 0), vertex_mark.assign(vertex.size(), 0);
    stamp += 2;
    // Many moved (the first smoothing's rounds: a fifth of the 1M dress): each
    // face and vertex asks its corners or faces in parallel, and the lists come
    // from marks in index order; few: the moved vertices' faces, serially.
    const bool many = moved.size() * 16 > vertex.size();
    std::vector<Index> turned, corners;
    if (many) {
      parallel_for(0, moved.size(), kFoldGrain, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) vertex_mark[moved[k]] = stamp - 1;  // moved lists each vertex once
      });
      turned = marked(face_mark, stamp - 1, [&](Index f) {
        const auto c = g.faces.row(f);
        return std::any_of(c.begin(), c.end(), [&](Index v) { return vertex_mark[v] == stamp - 1; });
      });
    } else {
      for (Index v : moved)
        for (Index f : faces_of_vertex.row(v))
          if (face_mark[f] != stamp - 1) face_mark[f] = stamp - 1, turned.push_back(f);
    }
    parallel_for(0, turned.size(), 1024, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) face[turned[i]] = face_normal(positions, g.faces.row(turned[i]));
    });
    if (many) {
      corners = marked(vertex_mark, stamp, [&](Index v) {
        const auto fs = faces_of_vertex.row(v);
        return std::any_of(fs.begin(), fs.end(), [&](Index f) { return face_mark[f] == stamp - 1; });
      });
    } else {
      for (Index f : turned)
        for (Index v : g.faces.row(f))
          if (vertex_mark[v] != stamp) vertex_mark[v] = stamp, corners.push_back(v);
    }
    parallel_for(0, corners.size(), 1024, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) vertex[corners[i]] = sum_at(corners[i]);
    });
    std::vector<Index> retest;
    if (many) {
      retest = marked(face_mark, stamp, [&](Index f) {
        const auto c = g.faces.row(f);
        return std::any_of(c.begin(), c.end(), [&](Index v) { return vertex_mark[v] == stamp; });
      });
    } else {
      for (Index v : corners)
        for (Index f : faces_of_vertex.row(v))
          if (face_mark[f] != stamp) face_mark[f] = stamp, retest.push_back(f);
      std::sort(retest.begin(), retest.end());
    }
    return retest;
  }
  // The marks (of faces or vertices) for which `hit` is true set to `mark`, in
  // parallel (each its own); returns their indices ascending.
  template <class Hit>
  static std::vector<Index> marked(std::vector<std::uint32_t>& marks, std::uint32_t mark, const Hit& hit) {
    return gather_in_blocks<Index>(marks.size(), kFoldGrain, [&](std::size_t first, std::size_t last, std::vector<Index>& out) {
      for (std::size_t i = first; i < last; ++i)
        if (marks[i] != mark && hit(Index(i))) marks[i] = mark, out.push_back(Index(i));
    });
  }
  bool retested(Index f) const { return !face_mark.empty() && face_mark[f] == stamp; }
};

// How a face's neighbourhood (the corners of the faces around its corners)
// turned and grew from the original to `positions`: its best rotation
// (Eigen::umeyama) and the ratio of its spreads about its centre.
struct Similarity {
  Eigen::Matrix3d rotation;
  double scale;
};
Similarity hood_similarity(const Garment& g, const Csr& faces_of_vertex, const Points& positions,
                           std::span<const Index> face) {
  std::vector<Index> hood;
  for (Index v : face)
    for (Index f : faces_of_vertex.row(v))
      for (Index w : g.faces.row(f)) hood.push_back(w);
  std::sort(hood.begin(), hood.end());
  hood.erase(std::unique(hood.begin(), hood.end()), hood.end());
  Eigen::Matrix3Xd from(3, hood.size()), to(3, hood.size());
  for (std::size_t i = 0; i < hood.size(); ++i) {
    from.col(Eigen::Index(i)) = row3(g.positions, hood[i]);
    to.col(Eigen::Index(i)) = row3(positions, hood[i]);
  }
  const Eigen::Matrix3d rotation = Eigen::umeyama(from, to, false).topLeftCorner<3, 3>();
  const double s0 = (from.colwise() - from.rowwise().mean()).squaredNorm();
  const double s1 = (to.colwise() - to.rowwise().mean()).squaredNorm();
  return {rotation, s0 > 0.0 ? std::sqrt(s1 / s0) : 1.0};
}

// Whether face f points against its original normal turned as its
// neighbourhood turned.
bool turned_against_hood(const Orientation& o, const Points& positions, std::size_t f) {
  const auto face = o.g.faces.row(f);
  const Similarity sim = hood_similarity(o.g, o.faces_of_vertex, positions, face);
  return (sim.rotation * face_normal(o.g.positions, face)).dot(o.face[f]) <= 0.0;
}

// Folded: a face that agrees with its corners on the original (binding.agrees)
// and now points against them, or leans more than 60 degrees off them and points
// against its original normal turned as its neighbourhood turned. The second
// catches slivers of a split mesh whose neighbours turned with them (the 135k
// dress under the arms: 75-87 degrees off their corners, turned over against
// the neighbourhood); only faces that lean that far pay for the fit.
bool folded_now(const FoldBinding& binding, const Orientation& o, const Points& positions, std::size_t f) {
  if (!binding.agrees[f]) return false;
  if (!o.agrees(f)) return true;
  return !o.agrees(f, kSmoothAround) && turned_against_hood(o, positions, f);
}

// Faces flagged by `flag` (per face in `flags`, the list in `flagged`,
// ascending) after the vertices `moved` left `kept` for where `positions` has
// them now. Fewer flagged: the list is updated and true returned; else the
// move is undone (positions, orientation and flags as they were).
template <class Flag>
bool keep_if_fewer(Orientation& o, Points& positions, const std::vector<Index>& moved, const std::vector<Vec3>& kept,
                   std::vector<std::uint8_t>& flags, std::vector<Index>& flagged, const Flag& flag) {
  const std::vector<Index> retest = o.update(positions, moved);
  std::vector<std::uint8_t> was(retest.size());
  parallel_for(0, retest.size(), 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) was[i] = flags[retest[i]], flags[retest[i]] = flag(retest[i]);
  });
  const auto change = deterministic_sum<std::ptrdiff_t>(0, retest.size(), kFoldGrain, 0, [&](std::size_t i) {
    return std::ptrdiff_t(flags[retest[i]]) - std::ptrdiff_t(was[i]);
  });
  if (change >= 0) {  // no fewer flagged
    for (std::size_t k = 0; k < moved.size(); ++k) positions.row(moved[k]) = kept[k].transpose();
    o.update(positions, moved);
    for (std::size_t i = 0; i < retest.size(); ++i) flags[retest[i]] = was[i];
    return false;
  }
  std::vector<Index> now;  // the flagged faces not retested, and the retested ones flagged now
  for (Index f : flagged)
    if (!o.retested(f)) now.push_back(f);
  for (Index f : entries_where(retest, [&](Index f) { return flags[f] != 0; })) now.push_back(f);
  std::sort(now.begin(), now.end());
  flagged = std::move(now);
  return true;
}

// What the smoothing leaves: slivers of a split mesh, whose short edge (0.08 cm
// on the 135k dress's arm) turns over with a 0.05 cm difference of its corners'
// moves, which smoothing the moves over rings of 0.5 cm faces cannot even out
// that finely; and slivers left leaning more than 60 degrees off their corners,
// which the collision step's next round turns over (the 1M dress on F_thinner:
// 1 fold left by the smoothing, 31 after the round). Each face that agreed on
// the original and now leans that far takes its original shape, turned and
// scaled as its neighbourhood was from the original to now (hood_similarity),
// about its centre now; a corner of several takes the mean (in face order),
// pinned corners stay. A round that leaves no fewer such faces is undone and
// ends it. Returns the vertices moved.
std::vector<Index> reshape_leaning(const FoldBinding& binding, Orientation& o, Points& positions,
                                   const std::vector<std::uint8_t>* pinned, int rounds) {
  const Garment& g = o.g;
  const std::size_t nf = g.faces.rows();
  const auto leaning = [&](std::size_t f) { return binding.agrees[f] && !o.agrees(f, kSmoothAround); };
  std::vector<std::uint8_t> leans(nf, 0);
  parallel_for(0, nf, kFoldGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f) leans[f] = leaning(f);
  });
  std::vector<Index> lean, moved;
  for (std::size_t f = 0; f < nf; ++f)
    if (leans[f]) lean.push_back(Index(f));
  for (int round = 0; round < rounds && !lean.empty(); ++round) {
    std::vector<std::vector<Vec3>> target(lean.size());  // per face, its corners' (in the face's order)
    parallel_for(0, lean.size(), 16, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) {
        const auto face = g.faces.row(lean[k]);
        const Similarity sim = hood_similarity(g, o.faces_of_vertex, positions, face);
        Vec3 f0 = Vec3::Zero(), f1 = Vec3::Zero();
        for (Index v : face) f0 += row3(g.positions, v), f1 += row3(positions, v);
        f0 /= double(face.size());
        f1 /= double(face.size());
        for (Index v : face) target[k].push_back(f1 + sim.scale * (sim.rotation * (row3(g.positions, v) - f0)));
      }
    });
    std::vector<Index> corners;
    std::vector<Vec3> sum;
    std::vector<int> count;
    std::unordered_map<Index, std::size_t> slot;
    for (std::size_t k = 0; k < lean.size(); ++k) {
      const auto face = g.faces.row(lean[k]);
      for (std::size_t j = 0; j < face.size(); ++j) {
        if (pinned && (*pinned)[face[j]]) continue;
        const auto [it, fresh] = slot.emplace(face[j], corners.size());
        if (fresh) corners.push_back(face[j]), sum.push_back(Vec3::Zero()), count.push_back(0);
        sum[it->second] += target[k][j];
        ++count[it->second];
      }
    }
    if (corners.empty()) break;
    std::vector<Vec3> kept(corners.size());
    for (std::size_t c = 0; c < corners.size(); ++c) {
      kept[c] = row3(positions, corners[c]);
      positions.row(corners[c]) = (sum[c] / double(count[c])).transpose();
    }
    if (!keep_if_fewer(o, positions, corners, kept, leans, lean, leaning)) break;
    moved.insert(moved.end(), corners.begin(), corners.end());
  }
  return moved;
}

}  // namespace

std::vector<std::uint8_t> faces_agreeing(const Garment& g, const Csr& faces_of_vertex, const Points& positions) {
  const Orientation o(g, faces_of_vertex, positions);
  std::vector<std::uint8_t> agrees(g.faces.rows(), 0);
  parallel_for(0, agrees.size(), kFoldGrain, [&](std::size_t b, std::size_t e) {
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
  // Counted by folded_now; smoothed where turned against the corners (cheap to
  // retest: the reshaping takes the faces that only lean).
  const auto folded_at = [&](std::size_t f) { return folded_now(binding, o, positions, f); };
  const auto turned_at = [&](std::size_t f) { return binding.agrees[f] && !o.agrees(f); };
  std::vector<std::uint8_t> is_folded(nf, 0);  // here 1: turned, 2: only leaning and folded
  parallel_for(0, nf, kFoldGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t f = b; f < e; ++f)
      is_folded[f] = turned_at(f) ? 1 : binding.agrees[f] && !o.agrees(f, kSmoothAround) && turned_against_hood(o, positions, f) ? 2 : 0;
  });
  std::vector<Index> folded;
  for (std::size_t f = 0; f < nf; ++f) {
    rep.folded_before += is_folded[f] != 0;
    if ((is_folded[f] = is_folded[f] == 1)) folded.push_back(Index(f));
  }
  const std::size_t nv = std::size_t(positions.rows());
  std::vector<std::uint8_t> in(nv, 0), moved(nv, 0);
  constexpr Index kNoSlot = std::numeric_limits<Index>::max();
  std::vector<Index> slot(nv, kNoSlot);  // a vertex's place in a round's compact copies
  // Each round smooths the folded faces' corners and `rings` rings around them
  // times the round's number: a fold the last round left gets a wider region.
  // (Until 2026-12-01 the rings grew only from corners not yet in the region, so
  // a fold left over got none: the 4M dress on F_heavier kept 229 of its 21,284
  // folds through the five rounds; 103 now.)
  std::vector<Index> region;  // every round's, joined
  std::vector<std::uint32_t> reached(nv, 0);  // the last round whose rings reached a vertex
  constexpr std::uint32_t kFeathered = std::numeric_limits<std::uint32_t>::max();  // in this round's feather
  constexpr std::uint32_t kInPart = kFeathered - 1;  // in this round's part
  while (!folded.empty() && rep.rounds < options.max_rounds) {
    ++rep.rounds;
    const auto round = std::uint32_t(rep.rounds);
    std::vector<Index> front;
    const auto sorted = std::ptrdiff_t(region.size());  // the rounds before: sorted, each vertex once
    const auto reach = [&](Index v) {
      if (reached[v] == round) return;
      reached[v] = round, front.push_back(v);
      if (!in[v]) in[v] = 1, region.push_back(v);
    };
    for (Index f : folded)
      for (Index v : g.faces.row(f)) reach(v);
    for (int r = 0; r < options.rings * rep.rounds; ++r) {
      std::vector<Index> ring;
      ring.swap(front);
      for (Index v : ring)
        for (Index w : adjacency.row(v)) reach(w);
    }
    std::sort(region.begin() + sorted, region.end());
    std::inplace_merge(region.begin(), region.begin() + sorted, region.end());
    // A later round smooths the pieces of the region (connected through its
    // vertices) that its rings reached, around the folds left; a piece with no
    // fold left is smoothed already. Smoothing the whole region again, the 1M
    // dress warped to F_thinner (50,147 folds, 556 after round 1) smoothed
    // 640-655k vertices in each of rounds 2 to 5 for a few hundred folds: 1.4 s
    // in all, now 1.2 s; in the pipeline (report collision_folds, both calls)
    // 1.27-1.70 s, now 0.76-0.95 s (bench/README.md).
    std::vector<Index> part;
    if (rep.rounds == 1) {
      part = region;
    } else {
      std::vector<Index> stack;
      for (Index v : region)
        if (reached[v] == round) reached[v] = kInPart, stack.push_back(v), part.push_back(v);
      while (!stack.empty()) {
        const Index v = stack.back();
        stack.pop_back();
        for (Index w : adjacency.row(v))
          if (in[w] && reached[w] != kInPart) reached[w] = kInPart, stack.push_back(w), part.push_back(w);
      }
      for (Index v : part) reached[v] = round;
      std::sort(part.begin(), part.end());
    }
    std::vector<Index> free;
    for (Index v : part)
      if (!(pinned && (*pinned)[v]) && adjacency.row_size(v) > 0) free.push_back(v);
    // The feather: `feather` rings beyond the region, which take their
    // neighbours' mean move (not their mean displacement from the original:
    // their shape is kept), so the region's move eases off over them. With the
    // region's edge held instead, the move stopped within an edge there: on the
    // 1M dress on F_thinner the regions around the warp's crumples at the waist
    // are bands a few edges wide, and their edges showed as vertical pleats.
    std::vector<Index> band;
    {
      std::vector<Index> edge(part.begin(), part.end());
      for (int r = 0; r < options.feather; ++r) {
        std::vector<Index> next_ring;
        // The first ring's edge is the whole part (355k vertices of the 1M dress on F_thinner in round 1).
        for (Index w : neighbours_where(adjacency, edge, [&](Index w) { return reached[w] != round && reached[w] != kFeathered; }))
          if (reached[w] != kFeathered) reached[w] = kFeathered, next_ring.push_back(w);
        band.insert(band.end(), next_ring.begin(), next_ring.end());
        edge.swap(next_ring);
      }
      for (Index v : band) reached[v] = 0;  // before the rounds' marks again: 0 is no round's
      std::erase_if(band, [&](Index v) { return (pinned && (*pinned)[v]) || adjacency.row_size(v) == 0; });
      std::sort(band.begin(), band.end());
    }
    // One smoothing of `moving` (its first `eased_from` the region, the rest
    // the feather), kept when it leaves fewer folds.
    const auto smooth = [&](const std::vector<Index>& moving, std::size_t eased_from) {
      // The passes read the moving vertices and their neighbours from compact
      // copies (slot k < moving.size(): moving[k]; then the held neighbours): a
      // neighbour is one or two cache lines, not six of the column arrays (the
      // 1M dress on F_thinner: 10 passes over 207k vertices a round).
      std::vector<Index> local(moving.begin(), moving.end());
      parallel_for(0, moving.size(), kFoldGrain, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) slot[moving[k]] = Index(k);  // moving lists each vertex once
      });
      std::vector<std::size_t> first(moving.size() + 1, 0);
      for (std::size_t k = 0; k < moving.size(); ++k) first[k + 1] = first[k] + adjacency.row_size(moving[k]);
      for (Index w : neighbours_where(adjacency, moving, [&](Index w) { return slot[w] == kNoSlot; }))
        if (slot[w] == kNoSlot) slot[w] = Index(local.size()), local.push_back(w);
      std::vector<Index> near(first.back());
      // `next` and `now` take turns; both hold the held neighbours (slots past moving.size()) as they are.
      std::vector<Vec3> now(local.size()), from(local.size()), start(local.size()), next(local.size());
      parallel_for(0, local.size(), 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k)
          next[k] = now[k] = start[k] = row3(positions, local[k]), from[k] = row3(original, local[k]);
      });
      parallel_for(0, moving.size(), 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
          std::size_t at = first[k];
          for (Index w : adjacency.row(moving[k])) near[at++] = slot[w];
        }
      });
      parallel_for(0, local.size(), kFoldGrain, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) slot[local[k]] = kNoSlot;
      });
      const std::vector<Vec3> kept(now.begin(), now.begin() + std::ptrdiff_t(moving.size()));
      // A vertex takes base + mean(now - base) over its neighbours, base the
      // original for the region (their mean displacement) and the start for the
      // feather (their mean move). The neighbours' base sum does not change between
      // passes, so a pass reads only their positions: half the gathers of the
      // passes that are most of the smoothing's time.
      std::vector<Vec3> base_less_mean(moving.size());
      parallel_for(0, moving.size(), 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
          const std::vector<Vec3>& base = k < eased_from ? from : start;
          Vec3 sum = Vec3::Zero();
          for (std::size_t j = first[k]; j < first[k + 1]; ++j) sum += base[near[j]];
          const double n = double(first[k + 1] - first[k]);
          base_less_mean[k] = base[k] - sum / n;
        }
      });
      for (int pass = 0; pass < options.passes; ++pass) {
        parallel_for(0, moving.size(), 1024, [&](std::size_t b, std::size_t e) {
          for (std::size_t k = b; k < e; ++k) {
            Vec3 sum = Vec3::Zero();
            for (std::size_t j = first[k]; j < first[k + 1]; ++j) sum += now[near[j]];
            next[k] = base_less_mean[k] + sum / double(first[k + 1] - first[k]);
          }
        });
        now.swap(next);
      }
      parallel_for(0, moving.size(), 1024, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) positions.row(moving[k]) = now[k].transpose();
      });
      return keep_if_fewer(o, positions, moving, kept, is_folded, folded, turned_at);
    };
    // Where the region's move is large at its edge (a patch shifted several
    // edges), easing it off over a few rings can turn faces there over: that
    // round is smoothed again with the edge held.
    std::vector<Index> eased = free;
    eased.insert(eased.end(), band.begin(), band.end());
    bool kept_round = smooth(eased, free.size());
    if (kept_round) free = std::move(eased);
    else if (!band.empty()) kept_round = smooth(free, free.size());
    if (!kept_round) break;
    for (Index v : free) moved[v] = 1;
  }
  for (Index v : reshape_leaning(binding, o, positions, pinned, options.reshape_rounds)) moved[v] = 1;
  rep.smoothed = std::size_t(std::count(moved.begin(), moved.end(), 1));
  // The folds left: among the ones the smoothing left, and the faces around what the reshaping moved.
  std::vector<std::uint8_t> left(nf, 0);
  for (Index f : folded) left[f] = 1;
  rep.folded_after = deterministic_sum<std::size_t>(0, nf, kFoldGrain, 0, [&](std::size_t f) -> std::size_t {
    const auto face = g.faces.row(f);
    const bool around = left[f] || std::any_of(face.begin(), face.end(), [&](Index v) { return moved[v] != 0; });
    return around && folded_at(f) ? 1 : 0;
  });
  return rep;
}

}  // namespace refit
