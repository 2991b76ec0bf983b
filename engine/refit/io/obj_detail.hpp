#pragma once
// Internal to the garment OBJ reader and writers (obj_read.cpp, obj_write.cpp,
// obj_stream.cpp): the chunks of whole lines a file is parsed and written in, so
// that the in-memory and the streamed ways see the same chunks, elements, errors
// and warnings, and write the same bytes.
#include <refit/io/obj_garment.hpp>

#include <bit>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace refit::obj_detail {

// Chunks of whole lines are parsed and formatted independently. The chunk
// boundaries depend only on the text, so results do not depend on the threads.
inline constexpr std::size_t kChunkBytes = std::size_t(1) << 18;
inline constexpr std::size_t kMaxWarnings = 20;

// A written coordinate is kept as its text when its bits are the original's.
inline bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

struct ParseFailure {
  std::size_t line;  // 1-based, local to the chunk
  std::string message;
};

struct Chunk {
  // pass 1
  std::size_t lines = 0, nv = 0, nvt = 0, nvn = 0, nf = 0;
  // pass 2 (positions, normals and their spans go straight into the sink)
  std::vector<Index> face_sizes, face_v, face_n, line_sizes, line_v, point_sizes, point_v;
  bool any_normal = false;
  std::vector<std::pair<std::size_t, std::string>> warnings;  // local line, text (the first few)
  std::size_t unknown = 0;                                      // unknown statements
  std::optional<ParseFailure> failure;
};

struct Totals {
  std::size_t v = 0, vt = 0, vn = 0;
};

/// Where pass 2 writes `v` and `vn` data: row (global number - base).
struct Sink {
  Points& positions;
  Points& normals;
  std::vector<ObjSource::Span>& vspans;
  std::vector<ObjSource::Span>& nspans;
  std::size_t vertex_base = 0, normal_base = 0;
  bool starts_file = true;  // the text begins at the file's start (where a byte-order mark may be)
};

/// The end of the chunk that starts at `begin` in a text of `size` bytes:
/// kChunkBytes on, then past the next '\n' (`find_newline(at)`: offset of the
/// first '\n' at or after `at`, or `size`).
template <class FindNewline>
std::size_t chunk_end(std::size_t begin, std::size_t size, FindNewline&& find_newline) {
  std::size_t b = begin + kChunkBytes;
  if (b < size) {
    const std::size_t nl = find_newline(b);
    b = nl < size ? nl + 1 : size;
  }
  return std::min(b, size);
}

/// Pass 1: lines and v, vt, vn, f statements of text[begin, end).
void count_chunk(std::string_view text, std::size_t begin, std::size_t end, Chunk& c, bool starts_file = true);

/// Pass 2: the statements of text[begin, end) (spans are offsets into `text`),
/// with `before` the counts of the chunks before it and `totals` of the file.
/// `vertices_only`: v and vn statements only (a writer re-finding their spans
/// in a file already read). A problem goes to c.failure.
void parse_chunk(std::string_view text, std::size_t begin, std::size_t end, Chunk& c, const Sink& sink, Totals before,
                 Totals totals, bool vertices_only = false);

inline void append_number(std::string& out, double x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, r.ptr);
}

inline void append_xyz(std::string& out, double x, double y, double z) {
  append_number(out, x);
  out.push_back(' ');
  append_number(out, y);
  out.push_back(' ');
  append_number(out, z);
}

/// Appends text[pos, end) to `out` with the x y z of each vertex v in
/// [v_begin, v_end) for which s.moved(v) replaced by s.position(v) at
/// s.vertex_span(v), and of each normal in [n_begin, n_end) for which
/// s.recomputed(n) by s.normal(n) at s.normal_span(n) (spans: offsets into
/// `text`, in file order). The writers' one way of giving a file back line for line.
template <class Edits>
void splice_chunk(std::string_view text, std::size_t pos, std::size_t end, std::size_t v_begin, std::size_t v_end,
                  std::size_t n_begin, std::size_t n_end, const Edits& s, std::string& out) {
  std::size_t vi = v_begin, ni = n_begin;
  while (vi < v_end || ni < n_end) {
    const bool vertex = ni >= n_end || (vi < v_end && s.vertex_span(vi).begin < s.normal_span(ni).begin);
    const std::size_t i = vertex ? vi++ : ni++;
    if (vertex ? !s.moved(i) : !s.recomputed(i)) continue;
    const ObjSource::Span sp = vertex ? s.vertex_span(i) : s.normal_span(i);
    const Vec3 p = vertex ? s.position(i) : s.normal(i);
    out.append(text.substr(pos, sp.begin - pos));
    append_xyz(out, p.x(), p.y(), p.z());
    pos = sp.end;
  }
  out.append(text.substr(pos, end - pos));
}

/// Every chunk's hash (std::hash of its bytes) of `text` split at `bounds`, kept by
/// a released source; check_reread throws refit::Error naming the source's file
/// ("... changed while being resized; nothing written") when chunk `c` read
/// again differs.
std::vector<std::size_t> chunk_hashes(std::string_view text, const std::vector<std::size_t>& bounds);
void check_reread(const ObjSource& s, std::size_t c, std::string_view chunk);

/// The rows of the chunks' `sizes` and `indices` (pass 2) as one CSR, in chunk order.
void fill_csr(Csr& csr, std::vector<Chunk>& chunks, std::vector<Index> Chunk::*sizes, std::vector<Index> Chunk::*indices);

/// "file:line: text" warnings of the chunks, the first kMaxWarnings, then a count of the rest.
void add_chunk_warnings(const std::string& file, const Chunk& c, std::size_t first_line, std::vector<std::string>& out,
                        std::size_t& unknown);
void finish_warnings(const std::string& file, std::size_t unknown, std::vector<std::string>& out);

}  // namespace refit::obj_detail
