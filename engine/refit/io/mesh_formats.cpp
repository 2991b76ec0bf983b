#include <refit/io/mesh_formats.hpp>

#include <refit/core/error.hpp>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>

namespace refit {
namespace {

constexpr std::size_t kMaxCorners = 1000;  // of one polygon: more is a broken file, not a body

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Whitespace-separated words of a text, with the line they are on.
class Words {
 public:
  Words(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  std::optional<std::string_view> next() {
    while (at_ < text_.size() && is_space(text_[at_])) {
      if (text_[at_] == '\n') ++line_;
      ++at_;
    }
    if (at_ == text_.size()) return std::nullopt;
    const std::size_t from = at_;
    while (at_ < text_.size() && !is_space(text_[at_])) ++at_;
    return text_.substr(from, at_ - from);
  }
  std::string_view word(const char* what) {
    const auto w = next();
    if (!w) fail("the file ends where " + std::string(what) + " should be");
    return *w;
  }
  double number(const char* what) {
    const std::string_view w = word(what);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
    if (ec != std::errc() || end != w.data() + w.size()) fail("bad " + std::string(what) + " '" + std::string(w) + "'");
    return v;
  }
  long long integer(const char* what) {
    const std::string_view w = word(what);
    long long v = 0;
    const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
    if (ec != std::errc() || end != w.data() + w.size()) fail("bad " + std::string(what) + " '" + std::string(w) + "'");
    return v;
  }
  // The rest of the current line (for formats with extra numbers per line).
  std::string_view rest_of_line() {
    const std::size_t from = at_;
    while (at_ < text_.size() && text_[at_] != '\n') ++at_;
    return text_.substr(from, at_ - from);
  }
  std::size_t left() const { return text_.size() - at_; }
  std::size_t offset() const { return at_; }
  [[noreturn]] void fail(const std::string& problem) const {
    throw input_error(path_ + ":" + std::to_string(line_), problem);
  }

 private:
  std::string_view text_;
  const std::string& path_;
  std::size_t at_ = 0, line_ = 1;
};

[[noreturn]] void fail(const std::string& path, const std::string& problem) { throw input_error(path, problem); }

// A count from the file, checked against what the rest of the file can hold.
std::size_t counted(long long n, std::size_t least_bytes_each, std::size_t bytes_left, const char* what,
                    const std::string& path) {
  if (n < 0) fail(path, "negative " + std::string(what) + " count " + std::to_string(n));
  if (static_cast<double>(n) * static_cast<double>(least_bytes_each) > static_cast<double>(bytes_left))
    fail(path, "the header declares " + std::to_string(n) + " " + what + " but only " + std::to_string(bytes_left) +
                   " bytes follow");
  return static_cast<std::size_t>(n);
}

Index corner(long long i, std::size_t vertices, const std::string& path) {
  if (i < 0 || static_cast<std::size_t>(i) >= vertices)
    fail(path, "face corner " + std::to_string(i) + " out of range (" + std::to_string(vertices) + " vertices)");
  return static_cast<Index>(i);
}

// --- PLY -----------------------------------------------------------------

enum class Scalar { i8, u8, i16, u16, i32, u32, f32, f64 };

std::optional<Scalar> scalar_of(std::string_view t) {
  static const std::pair<const char*, Scalar> kNames[] = {
      {"char", Scalar::i8},    {"int8", Scalar::i8},     {"uchar", Scalar::u8},   {"uint8", Scalar::u8},
      {"short", Scalar::i16},  {"int16", Scalar::i16},   {"ushort", Scalar::u16}, {"uint16", Scalar::u16},
      {"int", Scalar::i32},    {"int32", Scalar::i32},   {"uint", Scalar::u32},   {"uint32", Scalar::u32},
      {"float", Scalar::f32},  {"float32", Scalar::f32}, {"double", Scalar::f64}, {"float64", Scalar::f64}};
  for (const auto& [name, s] : kNames)
    if (t == name) return s;
  return std::nullopt;
}

std::size_t size_of(Scalar s) {
  switch (s) {
    case Scalar::i8: case Scalar::u8: return 1;
    case Scalar::i16: case Scalar::u16: return 2;
    case Scalar::i32: case Scalar::u32: case Scalar::f32: return 4;
    case Scalar::f64: return 8;
  }
  return 1;
}

struct Property {
  std::string name;
  Scalar type = Scalar::f32;
  bool list = false;
  Scalar count_type = Scalar::u8;
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
};

enum class Encoding { ascii, little, big };

// Values of a PLY body, ASCII or binary, in file order.
class PlyValues {
 public:
  PlyValues(std::string_view body, Encoding enc, const std::string& path)
      : words_(body, path), bytes_(body), enc_(enc), path_(path) {}
  double value(Scalar s) {
    if (enc_ == Encoding::ascii) return words_.number("a value");
    const std::size_t n = size_of(s);
    if (bytes_.size() - at_ < n) fail(path_, "the file ends inside the element data");
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + at_, n);
    at_ += n;
    if ((enc_ == Encoding::big) == (std::endian::native == std::endian::little)) std::reverse(b, b + n);
    switch (s) {
      case Scalar::i8: return static_cast<std::int8_t>(b[0]);
      case Scalar::u8: return b[0];
      case Scalar::i16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
      case Scalar::u16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
      case Scalar::i32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
      case Scalar::u32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
      case Scalar::f32: { float v; std::memcpy(&v, b, 4); return v; }
      case Scalar::f64: { double v; std::memcpy(&v, b, 8); return v; }
    }
    return 0.0;
  }
  long long integer(Scalar s, const char* what) {
    const double v = value(s);
    if (!(std::floor(v) == v) || std::abs(v) > 9e15) fail(path_, std::string("bad ") + what + " " + std::to_string(v));
    return static_cast<long long>(v);
  }
  std::size_t left() const { return enc_ == Encoding::ascii ? words_.left() : bytes_.size() - at_; }

 private:
  Words words_;
  std::string_view bytes_;
  std::size_t at_ = 0;
  Encoding enc_;
  const std::string& path_;
};

}  // namespace

BodyMesh parse_ply(std::string_view bytes, const std::string& path) {
  const std::size_t end = bytes.find("end_header");
  if (bytes.substr(0, 3) != "ply" || end == std::string_view::npos)
    fail(path, bytes.substr(0, 3) != "ply" ? "not a PLY file (it does not start with 'ply')" : "the PLY header has no end_header");
  std::size_t body_at = bytes.find('\n', end);
  body_at = body_at == std::string_view::npos ? bytes.size() : body_at + 1;
  Words header(bytes.substr(0, end), path);
  header.word("ply");
  std::optional<Encoding> enc;
  std::vector<Element> elements;
  while (const auto w = header.next()) {
    if (*w == "comment" || *w == "obj_info") {
      header.rest_of_line();
    } else if (*w == "format") {
      const std::string_view f = header.word("the format");
      enc = f == "ascii" ? Encoding::ascii : f == "binary_little_endian" ? Encoding::little
            : f == "binary_big_endian" ? std::optional(Encoding::big) : std::nullopt;
      if (!enc || header.word("the format version") != "1.0") header.fail("unknown PLY format '" + std::string(f) + "'");
    } else if (*w == "element") {
      Element e;
      e.name = header.word("an element name");
      const long long n = header.integer("element count");
      if (n < 0) header.fail("negative element count " + std::to_string(n));
      e.count = static_cast<std::size_t>(n);
      elements.push_back(std::move(e));
    } else if (*w == "property") {
      if (elements.empty()) header.fail("a property before any element");
      Property p;
      std::string_view t = header.word("a property type");
      if (t == "list") {
        p.list = true;
        const auto ct = scalar_of(header.word("a list count type"));
        if (!ct) header.fail("unknown list count type");
        p.count_type = *ct;
        t = header.word("a list item type");
      }
      const auto s = scalar_of(t);
      if (!s) header.fail("unknown property type '" + std::string(t) + "'");
      p.type = *s;
      p.name = header.word("a property name");
      elements.back().properties.push_back(std::move(p));
    } else {
      header.fail("'" + std::string(w->substr(0, 40)) + "' is not a PLY header keyword");
    }
  }
  if (!enc) fail(path, "the PLY header has no format line");

  PlyValues values(bytes.substr(body_at), *enc, path);
  BodyMesh body;
  std::size_t vertices = 0;
  for (const Element& e : elements) {
    // Each element takes at least one byte per property in binary, two in ASCII.
    const std::size_t least = std::max<std::size_t>(1, e.properties.size()) * (*enc == Encoding::ascii ? 2 : 1);
    counted(static_cast<long long>(std::min<std::size_t>(e.count, std::size_t(1) << 62)), least, values.left(),
            e.name == "vertex" ? "vertices" : e.name == "face" ? "faces" : "elements", path);
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int xyz[3] = {-1, -1, -1};
    int corners_at = -1;
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      if (is_vertex && !p.list && p.name.size() == 1 && p.name[0] >= 'x' && p.name[0] <= 'z') xyz[p.name[0] - 'x'] = int(k);
      if (is_face && p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) corners_at = int(k);
    }
    if (is_vertex) {
      if (e.count > 0 && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)) fail(path, "the vertex element has no x, y and z");
      vertices = e.count;
      body.vertices.resize(static_cast<Eigen::Index>(e.count), 3);
    }
    std::vector<Index> polygon;
    for (std::size_t i = 0; i < e.count; ++i)
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const Property& p = e.properties[k];
        if (!p.list) {
          const double v = values.value(p.type);
          for (int c = 0; c < 3; ++c)
            if (is_vertex && xyz[c] == int(k)) body.vertices(static_cast<Eigen::Index>(i), c) = v;
          continue;
        }
        const long long n = values.integer(p.count_type, "list length");
        if (n < 0 || n > static_cast<long long>(kMaxCorners))
          fail(path, "a list of " + std::to_string(n) + " items (at most " + std::to_string(kMaxCorners) + ")");
        polygon.clear();
        for (long long j = 0; j < n; ++j) {
          const long long c = values.integer(p.type, "face corner");
          if (int(k) == corners_at) polygon.push_back(corner(c, vertices, path));
        }
        if (int(k) == corners_at) fan_split(polygon, body.triangles);
      }
  }
  return body;
}

BodyMesh parse_off(std::string_view bytes, const std::string& path) {
  // Lines without comments, and the numbers on them.
  std::size_t at = 0, line_no = 0;
  std::string line;
  auto next_line = [&]() -> bool {
    while (at < bytes.size()) {
      const std::size_t nl = std::min(bytes.find('\n', at), bytes.size());
      line.assign(bytes.substr(at, nl - at));
      at = nl + 1;
      ++line_no;
      if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
      if (line.find_first_not_of(" \t\r\f\v") != std::string::npos) return true;
    }
    return false;
  };
  auto numbers = [&](std::size_t most) {
    std::vector<double> out;
    Words w(line, path);
    while (out.size() < most)
      if (const auto s = w.next()) {
        double v = 0.0;
        const auto [end, ec] = std::from_chars(s->data(), s->data() + s->size(), v);
        if (ec != std::errc() || end != s->data() + s->size())
          fail(path + ":" + std::to_string(line_no), "bad number '" + std::string(s->substr(0, 40)) + "'");
        out.push_back(v);
      } else {
        break;
      }
    return out;
  };
  if (!next_line()) fail(path, "not an OFF file (it is empty)");
  {
    Words first(line, path);
    const std::string key(first.word("OFF"));
    // nOFF (n dimensions) and 4OFF (homogeneous) are not 3D meshes.
    if (key.size() < 3 || key.compare(key.size() - 3, 3, "OFF") != 0 || key.find('4') != std::string::npos ||
        key.find('n') != std::string::npos)
      fail(path, "not an OFF file this reader knows (it starts with '" + key.substr(0, 20) + "')");
    line = std::string(first.rest_of_line());
  }
  if (line.find_first_not_of(" \t\r") == std::string::npos && !next_line())
    fail(path, "the OFF header needs vertex, face and edge counts");
  const std::vector<double> counts = numbers(3);
  if (counts.size() < 3) fail(path, "the OFF header needs vertex, face and edge counts");
  for (double c : counts)
    if (!(c >= 0.0) || std::floor(c) != c || c > 9e15) fail(path, "bad count in the OFF header");
  const std::size_t nv = counted(static_cast<long long>(counts[0]), 6, bytes.size() - std::min(at, bytes.size()),
                                 "vertices", path);
  const std::size_t nf = counted(static_cast<long long>(counts[1]), 2, bytes.size() - std::min(at, bytes.size()),
                                 "faces", path);
  BodyMesh body;
  body.vertices.resize(static_cast<Eigen::Index>(nv), 3);
  for (std::size_t i = 0; i < nv; ++i) {
    if (!next_line()) fail(path, "the file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
    const std::vector<double> p = numbers(3);
    if (p.size() < 3) fail(path + ":" + std::to_string(line_no), "a vertex needs three coordinates");
    for (int c = 0; c < 3; ++c) body.vertices(static_cast<Eigen::Index>(i), c) = p[static_cast<std::size_t>(c)];
  }
  std::vector<Index> polygon;
  for (std::size_t f = 0; f < nf; ++f) {
    if (!next_line()) fail(path, "the file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
    const std::vector<double> head = numbers(1);
    const double n = head.empty() ? -1.0 : head[0];
    if (!(n >= 0.0) || std::floor(n) != n || n > double(kMaxCorners))
      fail(path + ":" + std::to_string(line_no), "a face needs a corner count from 0 to " + std::to_string(kMaxCorners));
    const std::vector<double> c = numbers(1 + static_cast<std::size_t>(n));
    if (c.size() < 1 + static_cast<std::size_t>(n)) fail(path + ":" + std::to_string(line_no), "a face has fewer corners than its count");
    polygon.clear();
    for (std::size_t k = 1; k < c.size(); ++k) {
      if (std::floor(c[k]) != c[k]) fail(path + ":" + std::to_string(line_no), "a face corner is not an integer");
      polygon.push_back(corner(static_cast<long long>(std::clamp(c[k], -1.0, 9e15)), nv, path));
    }
    fan_split(polygon, body.triangles);
  }
  return body;
}

BodyMesh parse_stl(std::string_view bytes, const std::string& path) {
  BodyMesh body;
  std::map<std::array<double, 3>, Index> index_of;  // equal corners are one vertex
  std::vector<Vec3> points;
  auto vertex = [&](const std::array<double, 3>& p) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) fail(path, "a non-finite vertex coordinate");
    const auto [it, added] = index_of.emplace(p, static_cast<Index>(points.size()));
    if (added) points.emplace_back(p[0], p[1], p[2]);
    return it->second;
  };
  std::uint32_t declared = 0;
  if (bytes.size() >= 84) std::memcpy(&declared, bytes.data() + 80, 4);  // little-endian on every platform we build for
  const bool binary = bytes.size() >= 84 && 84.0 + 50.0 * declared == static_cast<double>(bytes.size());
  if (binary) {
    for (std::uint32_t t = 0; t < declared; ++t) {
      std::array<Index, 3> tri;
      for (int k = 0; k < 3; ++k) {
        float f[3];
        std::memcpy(f, bytes.data() + 84 + 50 * std::size_t(t) + 12 * std::size_t(k + 1), sizeof f);
        tri[static_cast<std::size_t>(k)] = vertex({f[0], f[1], f[2]});
      }
      body.triangles.push_back(tri);
    }
  } else if (bytes.substr(0, 5) == "solid") {
    Words w(bytes, path);
    std::vector<Index> polygon;
    while (const auto word = w.next()) {
      if (*word == "vertex") {
        std::array<double, 3> p;
        for (double& c : p) c = w.number("a vertex coordinate");
        polygon.push_back(vertex(p));
        if (polygon.size() > kMaxCorners) w.fail("a facet of more than " + std::to_string(kMaxCorners) + " corners");
      } else if (*word == "endloop") {
        fan_split(polygon, body.triangles);
        polygon.clear();
      }
    }
  } else {
    fail(path, bytes.size() < 84 ? "not an STL file (too short for a binary STL, and not 'solid ...')"
                                 : "the header declares " + std::to_string(declared) + " triangles but the file has " +
                                       std::to_string(bytes.size()) + " bytes, not " +
                                       std::to_string(84 + 50 * std::uint64_t(declared)));
  }
  body.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i) body.vertices.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  return body;
}

}  // namespace refit
