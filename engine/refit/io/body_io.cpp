#include <refit/body/body_mesh.hpp>
#include <refit/io/body_io.hpp>

#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/obj_garment.hpp>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

namespace refit {
namespace {

// Fan split a-b-c, a-c-d, ... of one polygon, the same for every format.
template <class Corners>
void fan_split(const Corners& c, std::vector<std::array<Index, 3>>& out) {
  for (std::size_t k = 1; k + 1 < c.size(); ++k) out.push_back({c[0], c[k], c[k + 1]});
}

BodyMesh read_obj_body(const std::string& path) {
  Garment g = read_garment_obj(path);
  BodyMesh body;
  body.vertices = std::move(g.positions);
  body.triangles.reserve(g.faces.indices.size());
  for (std::size_t f = 0; f < g.faces.rows(); ++f) fan_split(g.faces.row(f), body.triangles);
  return body;
}

// A header's element counts must fit in the file before OpenMesh allocates for
// them (issue 17: a 65-byte PLY declaring 99999999999 vertices grew to 9 GB).
// Each element takes at least `least` bytes: a PLY vertex one per property in
// binary and two ("0 ") in ASCII, a face one (its count byte) or two ("0\n"); an
// OFF vertex six ("0 0 0\n"); a binary STL triangle 50.
void check_declared_counts(const std::string& path, const std::string& ext) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw input_error(path, "cannot open: " + std::string(std::strerror(errno)));
  const auto size = static_cast<double>(std::filesystem::file_size(path));
  auto too_many = [&](double count, double least, const std::string& what) {
    if (count * least > size)
      throw input_error(path, "the header declares " + std::to_string(static_cast<long long>(std::min(count, 9e18))) +
                                  " " + what + " but the file has only " + std::to_string(static_cast<long long>(size)) +
                                  " bytes");
  };
  auto number = [&](const std::string& word, const std::string& what) {
    double v = -1.0;
    const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
    if (ec != std::errc() || end != word.data() + word.size() || !(v >= 0.0) || std::floor(v) != v)
      throw input_error(path, "bad " + what + " count '" + word + "' in the header");
    return v;
  };
  if (ext == ".stl") {
    char head[84] = {};
    in.read(head, sizeof head);
    if (std::string_view(head, std::min<std::size_t>(5, std::size_t(in.gcount()))) == "solid") return;  // ASCII
    if (in.gcount() < 84) throw input_error(path, "a binary STL needs an 84-byte header, the file has " +
                                                      std::to_string(in.gcount()) + " bytes");
    std::uint32_t triangles = 0;
    std::memcpy(&triangles, head + 80, 4);
    if (84.0 + 50.0 * triangles > size) too_many(triangles, size, "triangles");  // the message, always thrown
    return;
  }
  std::string line;
  if (ext == ".off") {
    // "[C][N][4]OFF [nv nf ne]" then, if not on that line, "nv nf ne" (comments start with #).
    std::vector<std::string> words;
    while (words.size() < 4 && std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ss(line);
      for (std::string w; ss >> w;) words.push_back(w);
      if (words.size() == 1 && words[0].find("OFF") == std::string::npos) break;
    }
    if (words.size() < 3 || words[0].find("OFF") == std::string::npos) return;  // OpenMesh names what is wrong
    too_many(number(words[1], "vertex"), 6.0, "vertices");
    too_many(number(words[2], "face"), 2.0, "faces");
    return;
  }
  // PLY: each element's count against its properties, until end_header.
  bool ascii = false;
  std::string name;
  double count = 0.0, props = 0.0;
  auto check = [&] {
    if (name.empty()) return;
    const double least = name == "face" ? (ascii ? 2.0 : 1.0) : (ascii ? 2.0 : 1.0) * std::max(props, 1.0);
    too_many(count, least, name == "vertex" ? "vertices" : name == "face" ? "faces" : "'" + name + "' elements");
  };
  for (int lines = 0; std::getline(in, line) && lines < 10000; ++lines) {
    std::istringstream ss(line);
    std::string key, a, b;
    ss >> key >> a >> b;
    if (key == "format") {
      ascii = a == "ascii";
    } else if (key == "element") {
      check();
      name = a;
      count = number(b, a);
      props = 0.0;
    } else if (key == "property") {
      props += 1.0;
    } else if (key == "end_header") {
      break;
    }
  }
  check();
}

BodyMesh read_openmesh_body(const std::string& path, const std::string& ext) {
  using Mesh = OpenMesh::PolyMesh_ArrayKernelT<>;
  Mesh mesh;
  OpenMesh::IO::Options options;
  if (!std::filesystem::exists(path)) throw input_error(path, "cannot open: no such file");
  check_declared_counts(path, ext);
  if (!OpenMesh::IO::read_mesh(mesh, path, options)) throw input_error(path, "cannot read the mesh (OpenMesh failed to parse it)");
  BodyMesh body;
  body.vertices.resize(static_cast<Eigen::Index>(mesh.n_vertices()), 3);
  for (const auto vh : mesh.vertices()) {
    const auto p = mesh.point(vh);
    for (int k = 0; k < 3; ++k) body.vertices(vh.idx(), k) = p[k];
  }
  std::vector<Index> corners;
  for (const auto fh : mesh.faces()) {
    corners.clear();
    // fv_range starts at the face's first vertex as given in the file.
    for (const auto vh : mesh.fv_range(fh)) corners.push_back(static_cast<Index>(vh.idx()));
    fan_split(corners, body.triangles);
  }
  return body;
}

void append_number(std::string& out, double x) {
  char buf[32];
  out.append(buf, std::to_chars(buf, buf + sizeof buf, x).ptr);
}

}  // namespace

BodyMesh read_body(const std::string& path) {
  const std::filesystem::path p(path);
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  BodyMesh body;
  if (ext == ".obj")
    body = read_obj_body(path);
  else if (ext == ".ply" || ext == ".off" || ext == ".stl")
    body = read_openmesh_body(path, ext);
  else
    throw input_error(path, "unknown body format '" + ext + "' (expected .obj, .ply, .off or .stl)");
  body.name = p.stem().string();
  body.path = path;
  check_body(body);
  return body;
}

void write_body_obj(const std::string& path, const BodyMesh& body) {
  for (Eigen::Index i = 0; i < body.vertices.rows(); ++i)
    if (!body.vertices.row(i).allFinite())
      throw input_error(path, "vertex " + std::to_string(i + 1) + " is NaN or infinite; nothing written");
  std::string text;
  text.reserve(static_cast<std::size_t>(body.vertices.rows()) * 40 + body.triangles.size() * 24);
  for (Eigen::Index i = 0; i < body.vertices.rows(); ++i) {
    text += "v";
    for (int k = 0; k < 3; ++k) {
      text += ' ';
      append_number(text, body.vertices(i, k));
    }
    text += '\n';
  }
  for (const auto& t : body.triangles) {
    text += "f";
    for (Index c : t) {
      text += ' ';
      text += std::to_string(std::size_t(c) + 1);
    }
    text += '\n';
  }
  write_file_atomically(path, [&](std::ostream& out) { out.write(text.data(), static_cast<std::streamsize>(text.size())); });
}

}  // namespace refit
