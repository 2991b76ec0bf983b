#pragma once
// Body meshes from files: OBJ with the engine's own parser, PLY, OFF and STL
// with small readers of our own (mesh_formats.hpp). Polygons are fan-split
// (a-b-c, a-c-d, ...) the same way for every format, so two bodies with the same
// faces get the same triangles. Vertices stay in the file's units; a bad file is refit::Error naming it.
#include <refit/body/body_mesh.hpp>

#include <string>

namespace refit {

/// Reads a body (.obj, .ply, .off, .stl by extension, case-insensitive); name =
/// file stem, path = `path`. OBJ: `v` and `f` (any index form) are used; vt, vn,
/// l and p are ignored. Throws refit::Error naming the file (and line for OBJ)
/// when it cannot be read, is malformed, has a NaN/inf coordinate, an index out
/// of range, or no triangle.
BodyMesh read_body(const std::string& path);

/// Writes `body` as a plain OBJ (v and f lines, shortest round-trip numbers),
/// atomically. Throws refit::Error naming `path` on a non-finite vertex or an
/// I/O failure.
void write_body_obj(const std::string& path, const BodyMesh& body);

}  // namespace refit
