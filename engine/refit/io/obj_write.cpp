// Writing a garment OBJ: the source file's text with only the moved positions
// (and the normals they change) rewritten, or a plain OBJ; atomically.
#include <refit/io/obj_garment.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/obj_detail.hpp>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <utility>


namespace refit {
namespace {
using obj_detail::append_xyz;
using obj_detail::same_bits;

void append_index(std::string& out, std::size_t i) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, i);
  out.append(buf, r.ptr);
}

void check_finite(const Points& p, const std::string& where) {
  const std::size_t n = static_cast<std::size_t>(p.rows());
  constexpr std::size_t kGrain = 1 << 16;
  const std::size_t blocks = (n + kGrain - 1) / kGrain;
  std::vector<std::size_t> first_bad(blocks, n);
  parallel_for(0, blocks, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k)
      for (std::size_t i = k * kGrain; i < std::min(n, (k + 1) * kGrain); ++i) {
        const auto ii = static_cast<Eigen::Index>(i);
        if (!std::isfinite(p(ii, 0)) || !std::isfinite(p(ii, 1)) || !std::isfinite(p(ii, 2))) {
          first_bad[k] = i;
          break;
        }
      }
  });
  for (std::size_t i : first_bad)
    if (i < n) throw input_error(where, "vertex " + std::to_string(i + 1) + " has a non-finite coordinate; nothing written");
}

// The output in parts (one per chunk of the source, or per block of elements),
// each formatted on demand: a writer streams them without the whole file in memory.
struct Parts {
  std::size_t count = 0;
  PartFormatter format;
};

std::string join(const Parts& parts) {
  std::vector<std::string> text(parts.count);
  parallel_for(0, parts.count, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) parts.format(k, text[k]);
  });
  std::size_t total = 0;
  for (const auto& t : text) total += t.size();
  std::string out;
  out.reserve(total);
  for (auto& t : text) {
    out += t;
    std::string().swap(t);
  }
  return out;
}

// A plain OBJ for garments that come from no file.
Parts format_plain(const Garment& g, const Points& x) {
  const std::size_t nv = g.vertex_count();
  constexpr std::size_t kGrain = 1 << 15;
  const auto blocks = [](std::size_t n) { return (n + kGrain - 1) / kGrain; };
  const std::size_t bv = blocks(nv), bf = blocks(g.faces.rows()), bl = blocks(g.lines.rows()), bp = blocks(g.points.rows());
  const auto csr_part = [](const Csr& csr, const char* kw, std::size_t k, std::string& out) {
    for (std::size_t r = k * kGrain; r < std::min(csr.rows(), (k + 1) * kGrain); ++r) {
      out += kw;
      for (Index i : csr.row(r)) {
        out.push_back(' ');
        append_index(out, std::size_t(i) + 1);
      }
      out.push_back('\n');
    }
  };
  return {bv + bf + bl + bp, [&g, &x, nv, bv, bf, bl, csr_part](std::size_t k, std::string& out) {
            if (k < bv) {
              for (std::size_t i = k * kGrain; i < std::min(nv, (k + 1) * kGrain); ++i) {
                const auto ii = static_cast<Eigen::Index>(i);
                out += "v ";
                append_xyz(out, x(ii, 0), x(ii, 1), x(ii, 2));
                out.push_back('\n');
              }
            } else if (k < bv + bf) {
              csr_part(g.faces, "f", k - bv, out);
            } else if (k < bv + bf + bl) {
              csr_part(g.lines, "l", k - bv - bf, out);
            } else {
              csr_part(g.points, "p", k - bv - bf - bl, out);
            }
          }};
}

// Each referenced normal: the normalised sum of the area-weighted (Newell)
// normals of the faces whose corners use it. Sequential scatter in face order,
// so the sums are the same whatever the thread count.
std::vector<std::uint8_t> recompute_normals(const Garment& g, const Points& x, const ObjSource& s, Points& normals,
                                            ObjWriteReport& report) {
  const std::size_t nn = static_cast<std::size_t>(s.normals.rows());
  std::vector<std::uint8_t> recomputed(nn, 0);
  normals = Points::Zero(static_cast<Eigen::Index>(nn), 3);
  std::vector<std::uint8_t> used(nn, 0);
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    const Vec3 n = face_normal(x, g.faces.row(f));
    for (std::size_t k = g.faces.offsets[f]; k < g.faces.offsets[f + 1]; ++k) {
      const Index ni = s.corner_normals[k];
      if (ni == ObjSource::kNoNormal) continue;
      normals.row(ni) += n.transpose();
      used[ni] = 1;
    }
  }
  std::size_t degenerate = 0;
  for (std::size_t i = 0; i < nn; ++i) {
    if (!used[i]) continue;
    const double len = normals.row(static_cast<Eigen::Index>(i)).norm();
    if (len > 0 && std::isfinite(len)) {
      normals.row(static_cast<Eigen::Index>(i)) /= len;
      recomputed[i] = 1;
      ++report.normals_recomputed;
    } else {
      ++degenerate;
    }
  }
  if (degenerate > 0)
    report.warnings.push_back(std::to_string(degenerate) +
                              " normals belong only to zero-area faces and were kept as they were");
  return recomputed;
}

Parts format_source(const Garment& g, const Points& x, const ObjSource& s, ObjWriteReport& report,
                    const std::string& where) {
  if (g.vertex_count() != s.vertex_spans.size())
    throw input_error(where, "the garment has " + std::to_string(g.vertex_count()) + " vertices but its source " +
                                 s.file + " has " + std::to_string(s.vertex_spans.size()) +
                                 "; it cannot be written back line for line");
  if (g.faces.indices.size() != s.face_corner_count)
    throw input_error(where, "the garment's faces differ from its source " + s.file +
                                 "; it cannot be written back line for line");
  const std::size_t nv = g.vertex_count();
  // Unmoved vertices keep their original text, so an unchanged garment is
  // written back byte for byte.
  std::vector<std::uint8_t> moved(nv, 0);
  const std::size_t moved_count = deterministic_sum<std::size_t>(0, nv, 1 << 15, 0, [&](std::size_t i) -> std::size_t {
    const auto ii = static_cast<Eigen::Index>(i);
    bool m = false;
    for (int k = 0; k < 3; ++k) m |= !same_bits(x(ii, k), s.positions(ii, k));
    moved[i] = m;
    return m ? 1 : 0;
  });
  Points normals;
  std::vector<std::uint8_t> recomputed;
  if (moved_count > 0 && !s.corner_normals.empty()) recomputed = recompute_normals(g, x, s, normals, report);

  // Shared by the copies of the formatter (std::function copies what it holds).
  struct Edits {
    std::vector<std::uint8_t> moved, recomputed;
    Points normals;
  };
  auto edits = std::make_shared<Edits>(Edits{std::move(moved), std::move(recomputed), std::move(normals)});
  // A released source is read again a chunk at a time (buffers the writer
  // reuses, not the whole file in fresh memory), each checked against its hash.
  std::shared_ptr<const SourceFile> file;
  if (s.released()) {
    file = std::make_shared<const SourceFile>(s.file);
    if (file->size() != s.text_size) throw input_error(s.file, "the file changed while being resized; nothing written");
  }
  return {s.chunk_begin.size() - 1, [&x, &s, edits, file](std::size_t c, std::string& out) {
            const std::size_t pos = s.chunk_begin[c], end = s.chunk_begin[c + 1];
            std::string chunk;
            std::string_view text = s.text.view();
            std::size_t base = 0;  // where `text` starts in the file
            if (file) {
              file->read(pos, end - pos, chunk);
              obj_detail::check_reread(s, c, chunk);
              text = chunk;
              base = pos;
            }
            out.reserve(end - pos + (end - pos) / 4);
            struct {
              const ObjSource& s;
              const Points& x;
              const Edits& e;
              std::size_t base;
              ObjSource::Span vertex_span(std::size_t i) const { return {s.vertex_spans[i].begin - base, s.vertex_spans[i].end - base}; }
              ObjSource::Span normal_span(std::size_t i) const { return {s.normal_spans[i].begin - base, s.normal_spans[i].end - base}; }
              bool moved(std::size_t i) const { return e.moved[i]; }
              bool recomputed(std::size_t i) const { return !e.recomputed.empty() && e.recomputed[i]; }
              Vec3 position(std::size_t i) const { return row3(x, Index(i)); }
              Vec3 normal(std::size_t i) const { return row3(e.normals, Index(i)); }
            } edit{s, x, *edits, base};
            obj_detail::splice_chunk(text, pos - base, end - base, s.chunk_first_vertex[c], s.chunk_first_vertex[c + 1],
                                     s.chunk_first_normal[c], s.chunk_first_normal[c + 1], edit, out);
          }};
}

Parts format_impl(const Garment& g, const Points& x, ObjWriteReport& report, const std::string& where) {
  check_finite(x, where);
  return g.source ? format_source(g, x, *g.source, report, where) : format_plain(g, x);
}

}  // namespace

std::string format_garment_obj(const Garment& g, ObjWriteReport* report) {
  ObjWriteReport local;
  return join(format_impl(g, g.positions, report ? *report : local, g.source ? g.source->file : std::string("<garment>")));
}

ObjWriteReport write_garment_obj(const std::string& path, const Garment& g) {
  return write_garment_obj(path, g, g.positions);
}

ObjWriteReport write_garment_obj(const std::string& path, const Garment& g, const Points& positions) {
  if (positions.rows() != g.positions.rows())
    throw input_error(path, "cannot write " + std::to_string(positions.rows()) + " positions for a garment of " +
                                std::to_string(g.positions.rows()) + " vertices");
  ObjWriteReport report;
  const Parts parts = format_impl(g, positions, report, path);
  write_parts_atomically(path, parts.count, parts.format);
  return report;
}

}  // namespace refit
