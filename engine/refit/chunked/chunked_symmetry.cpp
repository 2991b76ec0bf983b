#include <refit/chunked/chunked_symmetry.hpp>

#include <refit/attach/attachment.hpp>
#include <refit/core/error.hpp>
#include <refit/features/symmetry.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <memory>
#include <limits>
#include <queue>
#include <span>

namespace refit {
namespace {

constexpr Index kNoSlot = std::numeric_limits<Index>::max();

struct Query {
  Index vertex;
  std::array<double, 3> p;
};

struct Result {
  Index vertex;
  MirrorRecord record;
};

// Records appended to a temporary file through a buffer, read back in order.
template <class T>
class Spool {
 public:
  explicit Spool(const std::filesystem::path& folder) : file_(folder) {}
  void push(const T& t) {
    buffer_.push_back(t);
    if (buffer_.size() >= 4096) flush();
  }
  void flush() {
    file_.append(buffer_.data(), buffer_.size() * sizeof(T));
    count_ += buffer_.size();
    buffer_.clear();
  }
  // flush() for the last time, the buffer given back: a run keeps hundreds of
  // finished spools (a round's per slab), and their buffers held 250 MB of the
  // 4M dress's run under a 200 MB budget.
  void close() {
    flush();
    std::vector<T>().swap(buffer_);
  }
  std::size_t size() const { return count_ + buffer_.size(); }
  // Items [first, first + n) (after flush()).
  void read(std::size_t first, std::size_t n, std::vector<T>& out) const {
    out.resize(n);
    file_.read(out.data(), n * sizeof(T), first * sizeof(T));
  }

 private:
  TempFile file_;
  std::vector<T> buffer_;
  std::size_t count_ = 0;
};

// A slab's elements, in element order: per row its kind (0 face, 1 line, 2 point) and corners.
struct SlabElements {
  explicit SlabElements(const std::filesystem::path& folder) : words(folder) {}
  Spool<Index> words;  // kind, size, corners... per row
};

// The k-th smallest (0-based) of non-negative doubles on disk, by their bits (radix selection, 16 bits a pass).
double kth_smallest(const Spool<double>& values, std::size_t k) {
  std::uint64_t prefix = 0;
  std::vector<double> chunk;
  for (int shift = 48; shift >= 0; shift -= 16) {
    const std::uint64_t mask = shift == 48 ? 0 : ~std::uint64_t(0) << (shift + 16);
    std::vector<std::size_t> count(1 << 16, 0);
    for (std::size_t first = 0; first < values.size(); first += 1 << 20) {
      values.read(first, std::min<std::size_t>(1 << 20, values.size() - first), chunk);
      for (double d : chunk) {
        const std::uint64_t b = std::bit_cast<std::uint64_t>(d);
        if ((b & mask) == prefix) ++count[(b >> shift) & 0xffff];
      }
    }
    std::size_t bin = 0;
    while (k >= count[bin]) k -= count[bin++];
    prefix |= std::uint64_t(bin) << shift;
  }
  return std::bit_cast<double>(prefix);
}

}  // namespace

double MirrorRecord::distance() const {
  return Eigen::RowVector3d(offset[0], offset[1], offset[2]).norm();
}

ChunkedMirror chunked_mirror_attach(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan, double plane_x,
                                    double radius) {
  const std::filesystem::path& folder = plan.folder;
  const std::size_t n = g.vertex_count();
  ChunkedMirror out{RecordFile<MirrorRecord>(folder), 0.0, 0, 0};
  // Slabs along the longest axis of the garment and of its mirror image.
  Vec3 low = g.low(), high = g.high();
  low.x() = std::min(low.x(), 2.0 * plane_x - g.high().x());
  high.x() = std::max(high.x(), 2.0 * plane_x - g.low().x());
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (high[a] - low[a] > high[axis] - low[axis]) axis = a;
  const int axis2 = high[(axis + 1) % 3] - low[(axis + 1) % 3] >= high[(axis + 2) % 3] - low[(axis + 2) % 3] ? (axis + 1) % 3
                                                                                                          : (axis + 2) % 3;
  const std::size_t tile_elements = std::max<std::size_t>(plan.chunk_faces, 64);
  const double diagonal = (high - low).norm();
  const bool bare = g.face_count() + g.line_count() + g.point_count() == 0;
  const std::size_t elements = bare ? n : g.face_count() + g.line_count() + g.point_count();
  const std::size_t slabs = std::max<std::size_t>(1, (2 * elements + plan.chunk_faces - 1) / std::max<std::size_t>(plan.chunk_faces, 1));
  const double width = std::max(high[axis] - low[axis], 1e-300) / double(slabs);
  const auto slab_of = [&](double v) {
    return std::min<std::size_t>(slabs - 1, static_cast<std::size_t>(std::max(0.0, (v - low[axis]) / width)));
  };

  // Round 0 asks for every vertex's image; each round the images not found
  // within the radius ask again with four times the radius.
  auto pending = std::make_unique<Spool<Query>>(folder);
  for_each_chunk(g.positions(), plan.chunk_vertices, [&](std::size_t first, const Points& rows) {
    for (Eigen::Index i = 0; i < rows.rows(); ++i)
      pending->push({Index(first + std::size_t(i)), {2.0 * plane_x - rows(i, 0), rows(i, 1), rows(i, 2)}});
  });
  pending->close();
  std::vector<std::unique_ptr<Spool<Result>>> results;  // per round and slab, each in vertex order
  Spool<double> distances(folder);                     // of the images found
  const std::size_t rank = symmetry_percentile_rank(n);
  double r = std::max(radius, 1e-6 * diagonal);
  for (;; r *= 4.0, ++out.rounds) {
    const bool everything = r >= 2.0 * diagonal;  // every element reaches every slab: all found
    // This round's queries and elements, by slab.
    std::vector<std::unique_ptr<Spool<Query>>> queries;
    std::vector<std::unique_ptr<SlabElements>> slab_elements;
    for (std::size_t s = 0; s < slabs; ++s) {
      queries.push_back(std::make_unique<Spool<Query>>(folder));
      slab_elements.push_back(std::make_unique<SlabElements>(folder));
    }
    std::vector<Query> q;
    for (std::size_t first = 0; first < pending->size(); first += 1 << 16) {
      pending->read(first, std::min<std::size_t>(1 << 16, pending->size() - first), q);
      for (const Query& query : q) queries[slab_of(query.p[std::size_t(axis)])]->push(query);
    }
    const auto distribute = [&](const CsrFile& file, Index kind) {
      for_each_block(file, plan.chunk_faces, x, [&](const ElementBlock& b) {
        for (std::size_t e = 0; e < b.rows.rows(); ++e) {
          double lo = std::numeric_limits<double>::infinity(), hi = -lo;
          for (std::size_t c = b.rows.offsets[e]; c < b.rows.offsets[e + 1]; ++c) {
            lo = std::min(lo, b.corner(c)[axis]);
            hi = std::max(hi, b.corner(c)[axis]);
          }
          const std::size_t s0 = everything ? 0 : slab_of(lo - r * 1.000001), s1 = everything ? slabs - 1 : slab_of(hi + r * 1.000001);
          for (std::size_t s = s0; s <= s1; ++s) {
            Spool<Index>& w = slab_elements[s]->words;
            w.push(kind);
            w.push(Index(b.rows.row_size(e)));
            for (Index v : b.rows.row(e)) w.push(v);
          }
        }
      });
    };
    if (bare) {
      // A garment without elements attaches to its vertices (as GarmentLocator does).
      CsrFile points(folder);
      for (std::size_t first = 0; first < n; first += plan.chunk_vertices) {
        Csr rows;
        for (std::size_t i = first; i < std::min(n, first + plan.chunk_vertices); ++i) {
          const Index v = Index(i);
          rows.push_row(std::span<const Index>(&v, 1));
        }
        points.append(rows);
      }
      distribute(points, 2);
    } else {
      distribute(g.faces(), 0);
      distribute(g.lines(), 1);
      distribute(g.points(), 2);
    }
    auto next = std::make_unique<Spool<Query>>(folder);
    std::vector<Index> words, ids;
    std::vector<Query> slab_queries;
    for (std::size_t s = 0; s < slabs; ++s) {
      queries[s]->close();
      SlabElements& se = *slab_elements[s];
      se.words.close();
      if (queries[s]->size() == 0) continue;
      queries[s]->read(0, queries[s]->size(), slab_queries);
      // The slab's elements as a garment of their own, in element order.
      se.words.read(0, se.words.size(), words);
      Garment sub;
      ids.clear();
      for (std::size_t w = 0; w < words.size(); w += 2 + words[w + 1]) ids.insert(ids.end(), words.begin() + std::ptrdiff_t(w + 2), words.begin() + std::ptrdiff_t(w + 2 + words[w + 1]));
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      const auto local = [&](Index v) { return Index(std::lower_bound(ids.begin(), ids.end(), v) - ids.begin()); };
      std::vector<Index> row;
      for (std::size_t w = 0; w < words.size(); w += 2 + words[w + 1]) {
        row.clear();
        for (std::size_t c = 0; c < words[w + 1]; ++c) row.push_back(local(words[w + 2 + c]));
        (words[w] == 0 ? sub.faces : words[w] == 1 ? sub.lines : sub.points).push_row(row);
      }
      std::vector<Index>().swap(words);
      x.gather(ids, sub.positions);
      // Rounds after the first gather a slab's queries from several columns: in vertex order again.
      std::sort(slab_queries.begin(), slab_queries.end(), [](const Query& a, const Query& b) { return a.vertex < b.vertex; });
      // The images of `qs` (in vertex order) on the elements of `tile`, whose vertex k is the garment's `tile_ids[k]`.
      const auto attach_tile = [&](const Garment& tile, const std::vector<Index>& tile_ids, std::span<const Query> qs) {
        if (tile.faces.rows() + tile.lines.rows() + tile.points.rows() == 0) {
          for (const Query& query : qs) next->push(query);
          return;
        }
        auto found = std::make_unique<Spool<Result>>(folder);
        Points p(Eigen::Index(qs.size()), 3);
        for (std::size_t k = 0; k < qs.size(); ++k) p.row(Eigen::Index(k)) << qs[k].p[0], qs[k].p[1], qs[k].p[2];
        const SurfaceAttachment at = GarmentLocator(tile).attach(p);
        // Found: closer than the radius less a margin for rounding (an element
        // left out of the tile is farther than the radius).
        const double sure = r * (1.0 - 1e-9) - 1e-12 * diagonal;
        for (std::size_t k = 0; k < qs.size(); ++k) {
          MirrorRecord m;
          for (int j = 0; j < 3; ++j) {
            m.vertex[j] = tile_ids[at.vertex[k][j]];
            m.weight[j] = at.weight[k][j];
            m.offset[j] = at.offset(Eigen::Index(k), j);
          }
          const double d = m.distance();
          if (everything || d <= sure) {
            found->push({qs[k].vertex, m});
            distances.push(d);
          } else {
            next->push(qs[k]);
          }
        }
        found->close();
        results.push_back(std::move(found));
      };
      const std::size_t slab_element_count = sub.faces.rows() + sub.lines.rows() + sub.points.rows();
      if (everything || slab_element_count <= 2 * tile_elements || slab_queries.size() < 2) {
        attach_tile(sub, ids, slab_queries);
        continue;
      }
      // A slab through a dense part of the garment (with the elements within the
      // radius of it on both sides: the 4M dress's hips, a million faces in a
      // slab planned for 130 thousand) is cut again across, along the second
      // axis: each column takes its queries and the slab's elements within the
      // radius of them, so a tile's tree stays about a chunk's size. Above two
      // chunks' elements: at four the 13M dress under a 1 GB budget peaked at
      // 1045 MiB (at two 825), and each column repeats the radius's overlap (the
      // 1M dress under a 100 MB budget 8 % longer).
      const std::size_t columns = std::min(slab_queries.size(), (slab_element_count + tile_elements - 1) / tile_elements);
      std::vector<Query> across = slab_queries;
      std::stable_sort(across.begin(), across.end(),
                       [&](const Query& a, const Query& b) { return a.p[std::size_t(axis2)] < b.p[std::size_t(axis2)]; });
      std::vector<Index> slot(ids.size(), kNoSlot), col_ids, row2;
      for (std::size_t c = 0; c < columns; ++c) {
        std::vector<Query> group(across.begin() + std::ptrdiff_t(c * across.size() / columns),
                                 across.begin() + std::ptrdiff_t((c + 1) * across.size() / columns));
        if (group.empty()) continue;
        const double lo = group.front().p[std::size_t(axis2)] - r * 1.000001;
        const double hi = group.back().p[std::size_t(axis2)] + r * 1.000001;
        Garment col;
        col_ids.clear();
        const auto take = [&](const Csr& from, Csr& to) {
          for (std::size_t e = 0; e < from.rows(); ++e) {
            double emin = std::numeric_limits<double>::infinity(), emax = -emin;
            for (Index v : from.row(e)) {
              emin = std::min(emin, sub.positions(Eigen::Index(v), axis2));
              emax = std::max(emax, sub.positions(Eigen::Index(v), axis2));
            }
            if (emax < lo || emin > hi) continue;
            row2.clear();
            for (Index v : from.row(e)) {
              if (slot[v] == kNoSlot) slot[v] = Index(col_ids.size()), col_ids.push_back(v);
              row2.push_back(slot[v]);
            }
            to.push_row(row2);
          }
        };
        take(sub.faces, col.faces);
        take(sub.lines, col.lines);
        take(sub.points, col.points);
        col.positions.resize(Eigen::Index(col_ids.size()), 3);
        for (std::size_t k = 0; k < col_ids.size(); ++k) {
          col.positions.row(Eigen::Index(k)) = sub.positions.row(Eigen::Index(col_ids[k]));
          slot[col_ids[k]] = kNoSlot;
          col_ids[k] = ids[col_ids[k]];
        }
        std::sort(group.begin(), group.end(), [](const Query& a, const Query& b) { return a.vertex < b.vertex; });
        attach_tile(col, col_ids, group);
        ++out.columns;
      }
    }
    next->close();
    distances.flush();
    pending = std::move(next);
    if (pending->size() == 0 || distances.size() > rank) break;
  }
  // The rest were never found: no partner (an infinite distance).
  {
    auto rest = std::make_unique<Spool<Result>>(folder);
    std::vector<Query> q;
    MirrorRecord none;
    none.offset.fill(std::numeric_limits<double>::infinity());
    std::vector<Result> sorted;
    for (std::size_t first = 0; first < pending->size(); first += 1 << 16) {
      pending->read(first, std::min<std::size_t>(1 << 16, pending->size() - first), q);
      for (const Query& query : q) sorted.push_back({query.vertex, none});
    }
    std::sort(sorted.begin(), sorted.end(), [](const Result& a, const Result& b) { return a.vertex < b.vertex; });
    for (const Result& res : sorted) rest->push(res);
    rest->close();
    results.push_back(std::move(rest));
  }
  out.garment_error = n == 0 ? 0.0 : kth_smallest(distances, rank);
  // Every vertex's record, merged from the rounds' and slabs' lists (each in vertex order).
  // The lists' read buffers share a chunk's worth of records (a run of many
  // slabs and rounds has hundreds of lists).
  struct Cursor {
    const Spool<Result>* spool;
    std::size_t read_size;
    std::size_t next = 0;
    std::vector<Result> buffer;
    std::size_t at = 0;
    bool fill() {
      if (at < buffer.size()) return true;
      if (next >= spool->size()) return false;
      spool->read(next, std::min<std::size_t>(read_size, spool->size() - next), buffer);
      next += buffer.size();
      at = 0;
      return true;
    }
  };
  std::vector<Cursor> cursors;
  const std::size_t read_size = std::clamp<std::size_t>(plan.chunk_vertices / std::max<std::size_t>(results.size(), 1), 64, 1 << 12);
  for (const auto& r : results) cursors.push_back({r.get(), read_size, 0, {}, 0});
  const auto later = [&](std::size_t a, std::size_t b) {
    return cursors[a].buffer[cursors[a].at].vertex > cursors[b].buffer[cursors[b].at].vertex;
  };
  std::priority_queue<std::size_t, std::vector<std::size_t>, decltype(later)> heap(later);
  for (std::size_t c = 0; c < cursors.size(); ++c)
    if (cursors[c].fill()) heap.push(c);
  std::vector<MirrorRecord> block;
  std::size_t written = 0;
  while (!heap.empty()) {
    const std::size_t c = heap.top();
    heap.pop();
    Cursor& cur = cursors[c];
    if (cur.buffer[cur.at].vertex != written) throw Error("internal: the mirror images do not cover every vertex once");
    block.push_back(cur.buffer[cur.at].record);
    ++written;
    ++cur.at;
    if (cur.fill()) heap.push(c);
    if (block.size() == 1 << 14 || heap.empty()) {
      out.records.write(written - block.size(), std::span<const MirrorRecord>(block));
      block.clear();
    }
  }
  if (written != n) throw Error("internal: the mirror images do not cover every vertex");
  return out;
}

namespace {

// The images (carry_one's sums) of the rows of `rec` within `tolerance`, on `positions`.
Points images(const std::vector<MirrorRecord>& rec, const PointGather& positions, double tolerance) {
  std::vector<Index> ids;
  for (const MirrorRecord& m : rec)
    if (m.distance() <= tolerance) ids.insert(ids.end(), m.vertex.begin(), m.vertex.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  Points p;
  positions.gather(ids, p);
  Points out = Points::Zero(Eigen::Index(rec.size()), 3);
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const MirrorRecord& m = rec[i];
    if (!(m.distance() <= tolerance)) continue;
    Vec3 q(m.offset[0], m.offset[1], m.offset[2]);
    for (int k = 0; k < 3; ++k)
      q += m.weight[k] * row3(p, Index(std::lower_bound(ids.begin(), ids.end(), m.vertex[k]) - ids.begin()));
    out.row(Eigen::Index(i)) = q.transpose();
  }
  return out;
}

}  // namespace

Points symmetrised_move_rows(const RecordFile<MirrorRecord>& mirror, const PointGather& before, const PointGather& after,
                             std::size_t first, const Points& b, const Points& a, double tolerance) {
  std::vector<MirrorRecord> rec;
  mirror.read(first, std::size_t(b.rows()), rec);
  // As GarmentMirror::mirrored_move: the image's move (the offsets cancel), mirrored.
  Points mirrored = images(rec, after, tolerance) - images(rec, before, tolerance);
  mirrored.col(0) = -mirrored.col(0);
  Points out = a;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const auto r = Eigen::Index(i);
    if (!(rec[i].distance() <= tolerance)) continue;
    if ((a.row(r) - b.row(r)).isZero(0.0) && mirrored.row(r).isZero(0.0)) continue;  // as symmetrise_moves: the row stays
    out.row(r) = b.row(r) + 0.5 * (a.row(r) - b.row(r) + mirrored.row(r));
  }
  return out;
}

Points symmetrised_rows(const RecordFile<MirrorRecord>& mirror, const PointGather& positions, std::size_t first,
                        const Points& s, double plane_x, double tolerance) {
  std::vector<MirrorRecord> rec;
  mirror.read(first, std::size_t(s.rows()), rec);
  const Points image = images(rec, positions, 2.0 * tolerance);  // symmetrised_share's reach
  Points out = s;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const double share = symmetrised_share(rec[i].distance(), tolerance);
    if (!(share > 0.0)) continue;
    // carry_one's sum, then mirror_x.
    const auto r = Eigen::Index(i);
    Eigen::RowVector3d mirrored = image.row(r);
    mirrored(0) = (2.0 * plane_x) - image(r, 0);
    if (rec[i].distance() <= tolerance)
      out.row(r) = 0.5 * (s.row(r) + mirrored);
    else
      out.row(r) += (0.5 * share) * (mirrored - s.row(r));
  }
  return out;
}

}  // namespace refit
