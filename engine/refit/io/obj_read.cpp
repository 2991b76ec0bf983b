// Reading a garment OBJ: two parallel passes over chunks of whole lines (counts,
// then elements), keeping the file's text so that the writer can reproduce it.
#include <refit/io/obj_garment.hpp>

#include <refit/core/error.hpp>
#include <refit/io/obj_detail.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/atomic_file.hpp>

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
namespace obj_detail {
namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Splits one line (without its '\n') into whitespace-separated tokens; a token
/// starting with '#' ends the line (trailing comments).
struct Tokens {
  const char* p;
  const char* end;
  std::string_view next() {
    while (p < end && is_blank(*p)) ++p;
    if (p == end || *p == '#') return {};
    const char* s = p;
    while (p < end && !is_blank(*p)) ++p;
    return {s, static_cast<std::size_t>(p - s)};
  }
};

enum class Kind { kBlank, kV, kVt, kVn, kF, kL, kP, kKnown, kUnknown };

Kind classify(std::string_view kw) {
  if (kw.empty()) return Kind::kBlank;
  if (kw == "v") return Kind::kV;
  if (kw == "vt") return Kind::kVt;
  if (kw == "vn") return Kind::kVn;
  if (kw == "f") return Kind::kF;
  if (kw == "l") return Kind::kL;
  if (kw == "p") return Kind::kP;
  if (kw == "g" || kw == "o" || kw == "s" || kw == "usemtl" || kw == "mtllib") return Kind::kKnown;
  return Kind::kUnknown;
}

template <class F>
void for_each_line(const char* b, const char* e, F&& f) {
  while (b < e) {
    const char* nl = static_cast<const char*>(std::memchr(b, '\n', static_cast<std::size_t>(e - b)));
    const char* le = nl ? nl : e;
    f(b, le);
    b = nl ? nl + 1 : e;
  }
}

std::string quoted(std::string_view s) {
  if (s.size() > 40) s = s.substr(0, 40);
  std::string out(1, '\'');
  out.append(s);
  out.push_back('\'');
  return out;
}

// A UTF-8 byte-order mark before the file's first statement is not part of it
// (issue 17: it hid the first `v` line and shifted every face index).
const char* skip_byte_order_mark(const char* b, const char* e, const char* file_start) {
  return b == file_start && e - b >= 3 && std::memcmp(b, "\xEF\xBB\xBF", 3) == 0 ? b + 3 : b;
}

class ChunkParser {
 public:
  ChunkParser(std::string_view text, Chunk& out, const Sink& sink, Totals before, Totals totals, bool vertices_only)
      : text_(text), out_(out), sink_(sink), cur_(before), totals_(totals), vertices_only_(vertices_only) {}

  void parse(std::size_t begin, std::size_t end) {
    const char* base = text_.data();
    out_.face_sizes.reserve(out_.nf);
    out_.face_v.reserve(out_.nf * 4);
    try {
      for_each_line(base + begin, base + end, [&](const char* b, const char* e) {
        ++line_;
        statement(skip_byte_order_mark(b, e, sink_.starts_file ? base : nullptr), e);
      });
    } catch (const ParseFailure& f) {
      out_.failure = f;
    }
  }

 private:
  [[noreturn]] void fail(std::string message) const { throw ParseFailure{line_, std::move(message)}; }
  // More `v` or `vn` lines than the counting pass found (a file written to
  // between the passes, or a mapped one while it is parsed): never past the sink's rows.
  [[noreturn]] void changed() const { fail("the file changed while it was being read"); }

  double number(std::string_view tok, std::string_view kw) const {
    const char* b = tok.data();
    const char* e = b + tok.size();
    if (b < e && *b == '+') ++b;
    double x = 0;
    const auto [ptr, ec] = std::from_chars(b, e, x);
    if (ec == std::errc::result_out_of_range) fail("number " + quoted(tok) + " out of range in '" + std::string(kw) + "'");
    if (ec != std::errc() || ptr != e || b == e)
      fail("malformed number " + quoted(tok) + " in '" + std::string(kw) + "' statement");
    if (!std::isfinite(x)) fail("non-finite coordinate " + quoted(tok) + " in '" + std::string(kw) + "' statement");
    return x;
  }

  // Reads up to `max` numbers; returns how many, with the byte span of the first three.
  std::size_t numbers(Tokens& t, std::string_view kw, double* values, std::size_t max,
                      ObjSource::Span* span) const {
    std::size_t count = 0;
    for (std::string_view tok = t.next(); !tok.empty(); tok = t.next()) {
      if (count == max) fail("too many numbers in '" + std::string(kw) + "' statement");
      values[count] = number(tok, kw);
      if (span && count == 0) span->begin = static_cast<std::size_t>(tok.data() - text_.data());
      if (span && count == 2) span->end = static_cast<std::size_t>(tok.data() + tok.size() - text_.data());
      ++count;
    }
    return count;
  }

  // Turns a 1-based (or negative, relative) OBJ index into a 0-based one.
  Index resolve(long long raw, std::size_t cur, std::size_t total, const char* what) const {
    // "vertex" -> "vertices" (issue 17 found "vertexs"); "normal" -> "normals".
    auto count_of = [&](std::size_t n) {
      const std::string w(what);
      return std::to_string(n) + " " + (n == 1 ? w : w == "vertex" ? "vertices" : w + "s");
    };
    if (raw == 0) fail(std::string(what) + " index 0 is invalid (OBJ indices start at 1)");
    if (raw > 0) {
      if (static_cast<unsigned long long>(raw) > total)
        fail(std::string(what) + " index " + std::to_string(raw) + " out of range (the file has " + count_of(total) + ")");
      return static_cast<Index>(raw - 1);
    }
    // 0 - raw in unsigned arithmetic: -raw would overflow for LLONG_MIN.
    if (0ULL - static_cast<unsigned long long>(raw) > cur)
      fail("relative " + std::string(what) + " index " + std::to_string(raw) + " out of range (only " +
           count_of(cur) + " before this line)");
    return static_cast<Index>(static_cast<long long>(cur) + raw);
  }

  static bool integer(const char*& p, const char* e, long long& v) {
    if (p < e && *p == '+') ++p;
    const auto [ptr, ec] = std::from_chars(p, e, v);
    if (ec != std::errc() || ptr == p) return false;
    p = ptr;
    return true;
  }

  // One corner token: v, v/vt, v//vn or v/vt/vn (`allow_normal` false for `l`, `p`).
  void corner(std::string_view tok, std::string_view kw, bool allow_vt, bool allow_normal, Index& v,
              Index& vn, bool& has_vn) const {
    const char* p = tok.data();
    const char* e = p + tok.size();
    long long iv = 0, ivt = 0, ivn = 0;
    bool has_vt = false;
    has_vn = false;
    bool ok = integer(p, e, iv);
    if (ok && p < e) {
      ok = *p++ == '/';
      if (ok && p < e && *p == '/') {
        ++p;
        ok = integer(p, e, ivn);
        has_vn = true;
      } else if (ok) {
        ok = integer(p, e, ivt);
        has_vt = true;
        if (ok && p < e) {
          ok = *p++ == '/' && integer(p, e, ivn);
          has_vn = true;
        }
      }
    }
    if (!ok || p != e || (has_vt && !allow_vt) || (has_vn && !allow_normal))
      fail("malformed index " + quoted(tok) + " in '" + std::string(kw) + "' statement");
    v = resolve(iv, cur_.v, totals_.v, "vertex");
    if (has_vt) resolve(ivt, cur_.vt, totals_.vt, "texture coordinate");
    if (has_vn) vn = resolve(ivn, cur_.vn, totals_.vn, "normal");
  }

  void statement(const char* b, const char* e) {
    Tokens t{b, e};
    const std::string_view kw = t.next();
    double values[7];
    const Kind kind = classify(kw);
    if (vertices_only_ && kind != Kind::kV && kind != Kind::kVn) return;
    switch (kind) {
      case Kind::kBlank:
      case Kind::kKnown:
        return;
      case Kind::kUnknown:
        if (out_.unknown++ < kMaxWarnings)
          out_.warnings.emplace_back(line_, "unknown statement " + quoted(kw) + " kept verbatim");
        return;
      case Kind::kV: {
        ObjSource::Span span;
        const std::size_t n = numbers(t, kw, values, 7, &span);
        if (n < 3) fail("'v' needs 3 coordinates, found " + std::to_string(n));
        const std::size_t row = cur_.v - sink_.vertex_base;
        if (row >= sink_.vspans.size()) changed();
        for (int k = 0; k < 3; ++k) sink_.positions(static_cast<Eigen::Index>(row), k) = values[k];
        sink_.vspans[row] = span;
        ++cur_.v;
        return;
      }
      case Kind::kVt: {
        const std::size_t n = numbers(t, kw, values, 3, nullptr);
        if (n < 1) fail("'vt' needs 1 to 3 numbers, found none");
        ++cur_.vt;
        return;
      }
      case Kind::kVn: {
        ObjSource::Span span;
        const std::size_t n = numbers(t, kw, values, 3, &span);
        if (n != 3) fail("'vn' needs 3 numbers, found " + std::to_string(n));
        const std::size_t row = cur_.vn - sink_.normal_base;
        if (row >= sink_.nspans.size()) changed();
        for (int k = 0; k < 3; ++k) sink_.normals(static_cast<Eigen::Index>(row), k) = values[k];
        sink_.nspans[row] = span;
        ++cur_.vn;
        return;
      }
      case Kind::kF: {
        std::size_t n = 0;
        for (std::string_view tok = t.next(); !tok.empty(); tok = t.next(), ++n) {
          Index v = 0, vn = ObjSource::kNoNormal;
          bool has_vn = false;
          corner(tok, kw, true, true, v, vn, has_vn);
          out_.face_v.push_back(v);
          if (has_vn && !out_.any_normal) {
            out_.any_normal = true;
            out_.face_n.assign(out_.face_v.size() - 1, ObjSource::kNoNormal);
          }
          if (out_.any_normal) out_.face_n.push_back(vn);
        }
        if (n < 3) fail("face with " + std::to_string(n) + " vertices (needs at least 3)");
        out_.face_sizes.push_back(static_cast<Index>(n));
        return;
      }
      case Kind::kL:
      case Kind::kP: {
        const bool line = kw == "l";
        auto& indices = line ? out_.line_v : out_.point_v;
        std::size_t n = 0;
        for (std::string_view tok = t.next(); !tok.empty(); tok = t.next(), ++n) {
          Index v = 0, vn = 0;
          bool has_vn = false;
          corner(tok, kw, line, false, v, vn, has_vn);
          indices.push_back(v);
        }
        if (line && n < 2) fail("'l' with " + std::to_string(n) + " vertices (needs at least 2)");
        if (!line && n < 1) fail("'p' with no vertex");
        (line ? out_.line_sizes : out_.point_sizes).push_back(static_cast<Index>(n));
        return;
      }
    }
  }

  std::string_view text_;
  Chunk& out_;
  const Sink& sink_;
  Totals cur_, totals_;
  bool vertices_only_ = false;
  std::size_t line_ = 0;
};

}  // namespace

// Pass 1: lines and v/vt/vn counts of a chunk, so that pass 2 knows every
// chunk's starting counts and can resolve relative indices and ranges at once.
void count_chunk(std::string_view text, std::size_t begin, std::size_t end, Chunk& c, bool starts_file) {
  for_each_line(text.data() + begin, text.data() + end, [&](const char* b, const char* e) {
    ++c.lines;
    b = skip_byte_order_mark(b, e, starts_file ? text.data() : nullptr);
    while (b < e && is_blank(*b)) ++b;
    if (e - b < 2) return;
    if (*b == 'f' && is_blank(b[1])) ++c.nf;
    if (*b != 'v') return;
    if (is_blank(b[1])) {
      ++c.nv;
    } else if (e - b >= 3 && is_blank(b[2])) {
      if (b[1] == 't') ++c.nvt;
      if (b[1] == 'n') ++c.nvn;
    }
  });
}

void parse_chunk(std::string_view text, std::size_t begin, std::size_t end, Chunk& c, const Sink& sink, Totals before,
                 Totals totals, bool vertices_only) {
  ChunkParser(text, c, sink, before, totals, vertices_only).parse(begin, end);
}

void add_chunk_warnings(const std::string& file, const Chunk& c, std::size_t first_line, std::vector<std::string>& out,
                        std::size_t& unknown) {
  unknown += c.unknown;
  for (const auto& [line, w] : c.warnings)
    if (out.size() < kMaxWarnings) out.push_back(file + ":" + std::to_string(first_line + line) + ": " + w);
}

void finish_warnings(const std::string& file, std::size_t unknown, std::vector<std::string>& out) {
  if (unknown > out.size())
    out.push_back(file + ": " + std::to_string(unknown - out.size()) + " more unknown statements kept verbatim");
}

void fill_csr(Csr& csr, std::vector<Chunk>& chunks, std::vector<Index> Chunk::*sizes,
              std::vector<Index> Chunk::*indices) {
  std::vector<std::size_t> row0(chunks.size() + 1, 0), idx0(chunks.size() + 1, 0);
  for (std::size_t c = 0; c < chunks.size(); ++c) {
    row0[c + 1] = row0[c] + (chunks[c].*sizes).size();
    idx0[c + 1] = idx0[c] + (chunks[c].*indices).size();
  }
  csr.offsets.assign(row0.back() + 1, 0);
  csr.indices.resize(idx0.back());
  parallel_for(0, chunks.size(), 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c) {
      const auto& s = chunks[c].*sizes;
      const auto& ix = chunks[c].*indices;
      std::size_t off = idx0[c];
      for (std::size_t r = 0; r < s.size(); ++r) {
        off += s[r];
        csr.offsets[row0[c] + r + 1] = static_cast<Index>(off);
      }
      std::copy(ix.begin(), ix.end(), csr.indices.begin() + static_cast<std::ptrdiff_t>(idx0[c]));
    }
  });
}

std::vector<std::size_t> chunk_hashes(std::string_view text, const std::vector<std::size_t>& bounds) {
  std::vector<std::size_t> hash(bounds.empty() ? 0 : bounds.size() - 1);
  parallel_for(0, hash.size(), 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c)
      hash[c] = std::hash<std::string_view>{}(text.substr(bounds[c], bounds[c + 1] - bounds[c]));
  });
  return hash;
}

void check_reread(const ObjSource& s, std::size_t c, std::string_view chunk) {
  if (chunk.size() != s.chunk_begin[c + 1] - s.chunk_begin[c] || std::hash<std::string_view>{}(chunk) != s.chunk_hash[c])
    throw input_error(s.file, "the file changed while being resized; nothing written");
}

}  // namespace obj_detail

namespace {
using namespace obj_detail;

Garment parse_owned(TextBytes bytes, const std::string& file, SourceText keep) {
  const std::string_view text = bytes.view();
  const std::size_t n = text.size();
  auto src = std::make_shared<ObjSource>();
  src->file = file;
  std::vector<std::size_t>& bounds = src->chunk_begin;
  bounds.assign(1, 0);
  while (bounds.back() < n)
    bounds.push_back(chunk_end(bounds.back(), n, [&](std::size_t at) {
      const void* nl = std::memchr(text.data() + at, '\n', n - at);
      return nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - text.data()) : n;
    }));
  const std::size_t nc = bounds.size() - 1;
  std::vector<Chunk> chunks(nc);
  parallel_for(0, nc, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c) count_chunk(text, bounds[c], bounds[c + 1], chunks[c]);
  });
  std::vector<Totals> before(nc + 1);
  std::vector<std::size_t> line0(nc + 1, 0);
  for (std::size_t c = 0; c < nc; ++c) {
    before[c + 1] = {before[c].v + chunks[c].nv, before[c].vt + chunks[c].nvt, before[c].vn + chunks[c].nvn};
    line0[c + 1] = line0[c] + chunks[c].lines;
  }
  const Totals totals = before[nc];
  Garment g;
  g.positions.resize(static_cast<Eigen::Index>(totals.v), 3);
  src->normals.resize(static_cast<Eigen::Index>(totals.vn), 3);
  src->vertex_spans.resize(totals.v);
  src->normal_spans.resize(totals.vn);
  const Sink sink{g.positions, src->normals, src->vertex_spans, src->normal_spans};
  parallel_for(0, nc, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c)
      parse_chunk(text, bounds[c], bounds[c + 1], chunks[c], sink, before[c], totals);
  });
  for (std::size_t c = 0; c < nc; ++c)
    if (chunks[c].failure) throw input_error(file, chunks[c].failure->message, line0[c] + chunks[c].failure->line);
  if (totals.v == 0) throw input_error(file, "empty garment: the file has no vertices ('v' lines)");

  src->positions = g.positions;
  fill_csr(g.faces, chunks, &Chunk::face_sizes, &Chunk::face_v);
  fill_csr(g.lines, chunks, &Chunk::line_sizes, &Chunk::line_v);
  fill_csr(g.points, chunks, &Chunk::point_sizes, &Chunk::point_v);

  const bool any_normal = std::any_of(chunks.begin(), chunks.end(), [](const Chunk& c) { return c.any_normal; });
  if (any_normal) {
    src->corner_normals.reserve(g.faces.indices.size());
    for (const Chunk& c : chunks) {
      if (c.any_normal)
        src->corner_normals.insert(src->corner_normals.end(), c.face_n.begin(), c.face_n.end());
      else
        src->corner_normals.insert(src->corner_normals.end(), c.face_v.size(), ObjSource::kNoNormal);
    }
  }
  src->face_corner_count = g.faces.indices.size();
  src->chunk_first_vertex.resize(nc + 1);
  src->chunk_first_normal.resize(nc + 1);
  for (std::size_t c = 0; c <= nc; ++c) {
    src->chunk_first_vertex[c] = before[c].v;
    src->chunk_first_normal[c] = before[c].vn;
  }
  src->texcoords = totals.vt;
  std::size_t unknown = 0;
  for (std::size_t c = 0; c < nc; ++c) add_chunk_warnings(file, chunks[c], line0[c], src->warnings, unknown);
  finish_warnings(file, unknown, src->warnings);
  const std::size_t first_nl = text.find('\n');
  src->crlf = first_nl != std::string_view::npos && first_nl > 0 && text[first_nl - 1] == '\r';
  chunks.clear();
  src->text_size = n;
  if (keep == SourceText::kept) {
    src->text = std::move(bytes);
  } else {
    src->chunk_hash = chunk_hashes(text, bounds);
    bytes.check_unchanged();  // a mapped file: what was parsed and hashed is the file
  }
  g.source = std::move(src);
  return g;
}

}  // namespace

Garment parse_garment_obj(std::string_view text, const std::string& file_for_errors) {
  return parse_owned(TextBytes(text), file_for_errors, SourceText::kept);
}

Garment read_garment_obj(const std::string& path, SourceText text) {
  // Mapped only when released: kept text must not change under the writer.
  return parse_owned(read_file_bytes(path, text == SourceText::released), path, text);
}

std::string_view source_text(const ObjSource& s, TextBytes& store) {
  if (!s.released()) return s.text.view();
  store = read_file_bytes(s.file);
  const std::string_view text = store.view();
  if (text.size() != s.text_size) throw input_error(s.file, "the file changed while being resized; nothing written");
  parallel_for(0, s.chunk_hash.size(), 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c)
      obj_detail::check_reread(s, c, text.substr(s.chunk_begin[c], s.chunk_begin[c + 1] - s.chunk_begin[c]));
  });
  return text;
}

}  // namespace refit
