// Face corner texture coordinates and face groups, scanned from the kept OBJ
// text in the reader's chunks: pass 1 counts `vt` and `f` lines per chunk, pass
// 2 reads them at their global numbers. The reader validated the text already.
#include <refit/io/obj_attributes.hpp>

#include <refit/core/parallel.hpp>
#include <refit/io/obj_garment.hpp>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <map>
#include <string_view>

namespace refit {
namespace {

bool blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view next_token(const char*& p, const char* e) {
  while (p < e && blank(*p)) ++p;
  if (p == e || *p == '#') return {};
  const char* s = p;
  while (p < e && !blank(*p)) ++p;
  return {s, static_cast<std::size_t>(p - s)};
}

// The rest of a `g` / `o` line, trimmed, trailing comment dropped.
std::string rest_of_line(const char* p, const char* e) {
  std::string_view s(p, static_cast<std::size_t>(e - p));
  s = s.substr(0, s.find('#'));
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return std::string(s);
}

template <class F>
void for_each_line(std::string_view text, std::size_t begin, std::size_t end, F&& f) {
  const char* b = text.data() + begin;
  const char* e = text.data() + end;
  while (b < e) {
    const char* nl = static_cast<const char*>(std::memchr(b, '\n', static_cast<std::size_t>(e - b)));
    const char* le = nl ? nl : e;
    const char* p = b;
    const std::string_view kw = next_token(p, le);
    f(kw, p, le);
    b = nl ? nl + 1 : e;
  }
}

struct GroupEvent {
  std::size_t face;  // faces of the chunk before it
  bool object;       // `o` (else `g`)
  std::string name;
};

struct ChunkCounts {
  std::size_t vt = 0, faces = 0;
  std::vector<GroupEvent> events;
};

}  // namespace

ObjFaceAttributes obj_face_attributes(const Garment& g) {
  ObjFaceAttributes out;
  const std::size_t nfaces = g.faces.rows();
  if (!g.source || g.source->face_corner_count != g.faces.indices.size() || g.source->chunk_begin.size() < 2) {
    out.group_names = {""};
    out.face_groups.assign(nfaces, 0);
    return out;
  }
  const ObjSource& src = *g.source;
  TextBytes reread;
  const std::string_view text = source_text(src, reread);
  const std::vector<std::size_t>& bounds = src.chunk_begin;
  const std::size_t nc = bounds.size() - 1;
  std::vector<ChunkCounts> counts(nc);
  parallel_for(0, nc, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c)
      for_each_line(text, bounds[c], bounds[c + 1], [&](std::string_view kw, const char* p, const char* le) {
        if (kw == "vt") ++counts[c].vt;
        else if (kw == "f") ++counts[c].faces;
        else if (kw == "g" || kw == "o") counts[c].events.push_back({counts[c].faces, kw == "o", rest_of_line(p, le)});
      });
  });
  std::vector<std::size_t> vt0(nc + 1, 0), face0(nc + 1, 0);
  for (std::size_t c = 0; c < nc; ++c) {
    vt0[c + 1] = vt0[c] + counts[c].vt;
    face0[c + 1] = face0[c] + counts[c].faces;
  }
  if (face0[nc] != nfaces) {  // not the text these faces came from
    out.group_names = {""};
    out.face_groups.assign(nfaces, 0);
    return out;
  }
  out.texcoords = Points::Zero(static_cast<Eigen::Index>(vt0[nc]), 3);
  out.corner_texcoords.assign(g.faces.indices.size(), ObjFaceAttributes::kNoTexcoord);
  std::vector<unsigned char> any(nc, 0);
  parallel_for(0, nc, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c) {
      std::size_t vt = vt0[c], face = face0[c];
      for_each_line(text, bounds[c], bounds[c + 1], [&](std::string_view kw, const char* p, const char* le) {
        if (kw == "vt") {
          for (int k = 0; k < 3; ++k) {
            std::string_view tok = next_token(p, le);
            if (tok.empty()) break;
            if (tok.front() == '+') tok.remove_prefix(1);
            double x = 0;
            std::from_chars(tok.data(), tok.data() + tok.size(), x);
            out.texcoords(static_cast<Eigen::Index>(vt), k) = x;
          }
          ++vt;
        } else if (kw == "f") {
          std::size_t corner = g.faces.offsets[face];
          for (std::string_view tok = next_token(p, le); !tok.empty(); tok = next_token(p, le), ++corner) {
            const std::size_t slash = tok.find('/');
            if (slash == std::string_view::npos || slash + 1 >= tok.size() || tok[slash + 1] == '/') continue;
            long long raw = 0;
            const char* s = tok.data() + slash + 1;
            if (*s == '+') ++s;
            std::from_chars(s, tok.data() + tok.size(), raw);
            const long long index = raw > 0 ? raw - 1 : static_cast<long long>(vt) + raw;
            out.corner_texcoords[corner] = static_cast<Index>(index);
            any[c] = 1;
          }
          ++face;
        }
      });
    }
  });
  if (std::find(any.begin(), any.end(), 1) == any.end()) out.corner_texcoords.clear();

  // Groups: the `o` and `g` names in force, carried from chunk to chunk.
  std::map<std::string, Index> ids;
  std::string object, group;
  const auto id_of = [&]() {
    const std::string name = object.empty() ? group : group.empty() || group == object ? object : object + "/" + group;
    auto [it, added] = ids.emplace(name, static_cast<Index>(out.group_names.size()));
    if (added) out.group_names.push_back(name);
    return it->second;
  };
  out.face_groups.resize(nfaces);
  Index current = id_of();
  for (std::size_t c = 0; c < nc; ++c) {
    std::size_t done = 0;
    for (const GroupEvent& ev : counts[c].events) {
      std::fill(out.face_groups.begin() + static_cast<std::ptrdiff_t>(face0[c] + done),
                out.face_groups.begin() + static_cast<std::ptrdiff_t>(face0[c] + ev.face), current);
      done = ev.face;
      if (ev.object) {
        object = ev.name;
        group.clear();
      } else {
        group = ev.name;
      }
      current = id_of();
    }
    std::fill(out.face_groups.begin() + static_cast<std::ptrdiff_t>(face0[c] + done),
              out.face_groups.begin() + static_cast<std::ptrdiff_t>(face0[c + 1]), current);
  }
  return out;
}

}  // namespace refit
