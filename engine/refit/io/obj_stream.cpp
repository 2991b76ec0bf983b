// Garment OBJ files read and written a group of chunks at a time (issue 14):
// the chunk table and counts first (pass 1), then the elements group by group
// (pass 2); a write formats each chunk of the source again from the file.
#include <refit/io/obj_stream.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/file_bytes.hpp>
#include <refit/io/obj_detail.hpp>

#include <algorithm>
#include <bit>
#include <cmath>

namespace refit {
namespace {
using namespace obj_detail;

}  // namespace

ObjStream::ObjStream(std::string path, std::size_t group_bytes)
    : file_(std::move(path)), group_bytes_(std::max(group_bytes, kChunkBytes)) {
  const SourceFile src(file_);
  bytes_ = src.size();
  chunk_begin_.assign(1, 0);
  while (chunk_begin_.back() < bytes_)
    chunk_begin_.push_back(chunk_end(chunk_begin_.back(), bytes_, [&](std::size_t at) { return src.find_newline(at); }));
  const std::size_t nc = chunk_begin_.size() - 1;
  set_group_bytes(group_bytes_);
  const std::size_t first_nl = src.find_newline(0);
  if (first_nl > 0 && first_nl < bytes_) {
    std::string before;
    src.read(first_nl - 1, 1, before);
    crlf_ = before[0] == '\r';
  }

  first_vertex_.assign(nc + 1, 0);
  first_texcoord_.assign(nc + 1, 0);
  first_normal_.assign(nc + 1, 0);
  first_line_.assign(nc + 1, 0);
  std::string text;
  for (std::size_t g = 0; g + 1 < group_first_chunk_.size(); ++g) {
    const std::size_t c0 = group_first_chunk_[g], c1 = group_first_chunk_[g + 1];
    src.read(chunk_begin_[c0], chunk_begin_[c1] - chunk_begin_[c0], text);
    std::vector<Chunk> chunks(c1 - c0);
    parallel_for(0, c1 - c0, 1, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k)
        count_chunk(text, chunk_begin_[c0 + k] - chunk_begin_[c0], chunk_begin_[c0 + k + 1] - chunk_begin_[c0], chunks[k],
                    c0 == 0);
    });
    for (std::size_t k = 0; k < chunks.size(); ++k) {
      const std::size_t c = c0 + k;
      first_vertex_[c + 1] = first_vertex_[c] + chunks[k].nv;
      first_texcoord_[c + 1] = first_texcoord_[c] + chunks[k].nvt;
      first_normal_[c + 1] = first_normal_[c] + chunks[k].nvn;
      first_line_[c + 1] = first_line_[c] + chunks[k].lines;
      faces_ += chunks[k].nf;
    }
  }
  vertices_ = first_vertex_[nc];
  texcoords_ = first_texcoord_[nc];
  normals_ = first_normal_[nc];
}

void ObjStream::set_group_bytes(std::size_t bytes) {
  group_bytes_ = std::max(bytes, kChunkBytes);
  const std::size_t nc = chunk_begin_.size() - 1;
  group_first_chunk_.assign(1, 0);
  while (group_first_chunk_.back() < nc) {
    std::size_t c = group_first_chunk_.back() + 1;
    while (c < nc && chunk_begin_[c + 1] - chunk_begin_[group_first_chunk_.back()] <= group_bytes_) ++c;
    group_first_chunk_.push_back(c);
  }
}

std::vector<std::string> ObjStream::read(const std::function<void(ObjGroup&)>& take) const {
  const SourceFile src(file_);
  if (src.size() != bytes_) throw input_error(file_, "the file changed while being read");
  const Totals totals{vertices_, texcoords_, normals_};
  std::vector<std::string> warnings;
  std::size_t unknown = 0, faces = 0, lines = 0, points = 0;
  std::string text;
  for (std::size_t g = 0; g + 1 < group_first_chunk_.size(); ++g) {
    const std::size_t c0 = group_first_chunk_[g], c1 = group_first_chunk_[g + 1], base = chunk_begin_[c0];
    src.read(base, chunk_begin_[c1] - base, text);
    ObjGroup group;
    group.first_vertex = first_vertex_[c0];
    group.positions.resize(Eigen::Index(first_vertex_[c1] - first_vertex_[c0]), 3);
    Points normals(Eigen::Index(first_normal_[c1] - first_normal_[c0]), 3);
    std::vector<ObjSource::Span> vspans(first_vertex_[c1] - first_vertex_[c0]), nspans(first_normal_[c1] - first_normal_[c0]);
    const Sink sink{group.positions, normals, vspans, nspans, first_vertex_[c0], first_normal_[c0], base == 0};
    std::vector<Chunk> chunks(c1 - c0);
    parallel_for(0, c1 - c0, 1, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) {
        const std::size_t c = c0 + k;
        const Totals before{first_vertex_[c], first_texcoord_[c], first_normal_[c]};
        parse_chunk(text, chunk_begin_[c] - base, chunk_begin_[c + 1] - base, chunks[k], sink, before, totals);
      }
    });
    for (std::size_t k = 0; k < chunks.size(); ++k)
      if (chunks[k].failure) throw input_error(file_, chunks[k].failure->message, first_line_[c0 + k] + chunks[k].failure->line);
    for (std::size_t k = 0; k < chunks.size(); ++k) add_chunk_warnings(file_, chunks[k], first_line_[c0 + k], warnings, unknown);
    fill_csr(group.faces, chunks, &Chunk::face_sizes, &Chunk::face_v);
    fill_csr(group.lines, chunks, &Chunk::line_sizes, &Chunk::line_v);
    fill_csr(group.points, chunks, &Chunk::point_sizes, &Chunk::point_v);
    if (std::any_of(chunks.begin(), chunks.end(), [](const Chunk& c) { return c.any_normal; })) {
      group.corner_normals.reserve(group.faces.indices.size());
      for (const Chunk& c : chunks) {
        if (c.any_normal)
          group.corner_normals.insert(group.corner_normals.end(), c.face_n.begin(), c.face_n.end());
        else
          group.corner_normals.insert(group.corner_normals.end(), c.face_v.size(), ObjSource::kNoNormal);
      }
    }
    chunks.clear();
    group.first_face = faces;
    group.first_line = lines;
    group.first_point = points;
    faces += group.faces.rows();
    lines += group.lines.rows();
    points += group.points.rows();
    take(group);
  }
  if (vertices_ == 0) throw input_error(file_, "empty garment: the file has no vertices ('v' lines)");
  finish_warnings(file_, unknown, warnings);
  return warnings;
}

void ObjStream::write(const std::string& path, const ObjEdits& edits) const {
  const SourceFile src(file_);
  if (src.size() != bytes_) throw input_error(file_, "the file changed while being resized; nothing written");
  const Totals totals{vertices_, texcoords_, normals_};
  // A group's worth of chunks formatted at once (the chunked mode's budget sets the group).
  const std::size_t batch = std::clamp<std::size_t>(group_bytes_ / kChunkBytes, 4, 64);
  write_parts_atomically(path, chunk_begin_.size() - 1, [&](std::size_t c, std::string& out) {
    std::string text;
    const std::size_t begin = chunk_begin_[c], size = chunk_begin_[c + 1] - begin;
    text.resize(size);
    if (transfer_all(src.fd(), text.data(), size, off_t(begin), false) != 0)
      throw input_error(file_, "cannot read the whole file (it changed while being resized); nothing written");
    const std::size_t nv = first_vertex_[c + 1] - first_vertex_[c], nn = first_normal_[c + 1] - first_normal_[c];
    // The chunk's v and vn values and where they are, found as the reader found them.
    Points original(Eigen::Index(nv), 3), original_normals(Eigen::Index(nn), 3);
    std::vector<ObjSource::Span> vspans(nv), nspans(nn);
    Chunk scan;
    const Sink sink{original, original_normals, vspans, nspans, first_vertex_[c], first_normal_[c], begin == 0};
    parse_chunk(text, 0, size, scan, sink, {first_vertex_[c], first_texcoord_[c], first_normal_[c]}, totals, true);
    if (scan.failure) throw input_error(file_, "it changed while being resized; nothing written");
    Points x(Eigen::Index(nv), 3), normals;
    edits.positions(first_vertex_[c], nv, x);
    std::vector<std::uint8_t> recomputed;
    if (edits.normals && nn > 0) {
      normals.resize(Eigen::Index(nn), 3);
      edits.normals(first_normal_[c], nn, normals, recomputed);
    }
    std::vector<std::uint8_t> moved(nv, 0);
    for (std::size_t i = 0; i < nv; ++i) {
      const auto r = Eigen::Index(i);
      if (!std::isfinite(x(r, 0)) || !std::isfinite(x(r, 1)) || !std::isfinite(x(r, 2)))
        throw input_error(path, "vertex " + std::to_string(first_vertex_[c] + i + 1) +
                                    " has a non-finite coordinate; nothing written");
      for (int k = 0; k < 3; ++k) moved[i] |= !same_bits(x(r, k), original(r, k));
    }
    struct {
      const std::vector<ObjSource::Span>& vspans;
      const std::vector<ObjSource::Span>& nspans;
      const std::vector<std::uint8_t>& is_moved;
      const std::vector<std::uint8_t>& is_recomputed;
      const Points& x;
      const Points& n;
      ObjSource::Span vertex_span(std::size_t i) const { return vspans[i]; }
      ObjSource::Span normal_span(std::size_t i) const { return nspans[i]; }
      bool moved(std::size_t i) const { return is_moved[i]; }
      bool recomputed(std::size_t i) const { return !is_recomputed.empty() && is_recomputed[i]; }
      Vec3 position(std::size_t i) const { return row3(x, Index(i)); }
      Vec3 normal(std::size_t i) const { return row3(n, Index(i)); }
    } edit{vspans, nspans, moved, recomputed, x, normals};
    out.reserve(size + size / 4);
    splice_chunk(text, 0, size, 0, nv, 0, nn, edit, out);
  }, batch);
}

}  // namespace refit
