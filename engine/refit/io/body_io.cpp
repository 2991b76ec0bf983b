#include <refit/body/body_mesh.hpp>
#include <refit/io/body_io.hpp>

#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/file_bytes.hpp>
#include <refit/io/mesh_formats.hpp>
#include <refit/io/obj_garment.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>

namespace refit {
namespace {

BodyMesh read_obj_body(const std::string& path) {
  Garment g = read_garment_obj(path);
  BodyMesh body;
  body.vertices = std::move(g.positions);
  body.triangles.reserve(g.faces.indices.size());
  for (std::size_t f = 0; f < g.faces.rows(); ++f) fan_split(g.faces.row(f), body.triangles);
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
  else if (ext == ".ply")
    body = parse_ply(read_file_bytes(path).view(), path);
  else if (ext == ".off")
    body = parse_off(read_file_bytes(path).view(), path);
  else if (ext == ".stl")
    body = parse_stl(read_file_bytes(path).view(), path);
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
