#include <refit/body/body_mesh.hpp>
#include <refit/io/body_io.hpp>

#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/obj_garment.hpp>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>

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

BodyMesh read_openmesh_body(const std::string& path) {
  using Mesh = OpenMesh::PolyMesh_ArrayKernelT<>;
  Mesh mesh;
  OpenMesh::IO::Options options;
  if (!std::filesystem::exists(path)) throw input_error(path, "cannot open: no such file");
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
    body = read_openmesh_body(path);
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
