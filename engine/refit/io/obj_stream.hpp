#pragma once
// Garment OBJ files larger than memory (issue 14, out-of-core chunking): read
// and written a group of whole-line chunks at a time, the very chunks the
// in-memory reader and writer use (obj_garment.hpp), so the elements, the
// errors and the warnings are theirs, and the written file is byte-identical
// to write_garment_obj's, while only one group of the file is in memory.
#include <refit/io/obj_garment.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace refit {

/// One group of whole-line chunks of a garment OBJ, parsed.
struct ObjGroup {
  std::size_t first_vertex = 0;  // global number (0-based) of the group's first `v`
  std::size_t first_face = 0, first_line = 0, first_point = 0;  // ... of its first f, l and p element
  Points positions;              // its `v` values, in file order
  Csr faces, lines, points;      // its elements, with global 0-based vertex indices
  /// Normal index of each face corner (ObjSource::kNoNormal where it has none);
  /// empty when no corner of the group has one.
  std::vector<Index> corner_normals;
};

/// What a streamed write changes, asked for by ranges (from several threads at once).
struct ObjEdits {
  /// The positions of vertices [first, first + count) (count rows).
  std::function<void(std::size_t first, std::size_t count, Points& out)> positions;
  /// The `vn` normals [first, first + count) and whether each was recomputed
  /// (an unset function: every normal stays as it is).
  std::function<void(std::size_t first, std::size_t count, Points& out, std::vector<std::uint8_t>& recomputed)> normals;
};

class ObjStream {
 public:
  /// Pass 1 over the file at `path`: its chunks and counts, reading about
  /// `group_bytes` at a time. Throws refit::Error naming the file when it
  /// cannot be read.
  explicit ObjStream(std::string path, std::size_t group_bytes = std::size_t(64) << 20);

  const std::string& file() const { return file_; }
  std::size_t bytes() const { return bytes_; }
  std::size_t vertex_count() const { return vertices_; }
  std::size_t normal_count() const { return normals_; }
  std::size_t texcoord_count() const { return texcoords_; }
  std::size_t face_count() const { return faces_; }  // `f` statements
  bool crlf() const { return crlf_; }
  std::size_t group_bytes() const { return group_bytes_; }
  /// Reads (and writes) about `bytes` at a time from now on (whole chunks, at least one).
  void set_group_bytes(std::size_t bytes);

  /// Pass 2: the elements, a group at a time in file order (the group may be
  /// moved from). Returns the warnings read_garment_obj gives. Throws
  /// refit::Error as read_garment_obj does (the same message and line) at the
  /// first problem, and for a file without vertices.
  std::vector<std::string> read(const std::function<void(ObjGroup&)>& take) const;

  /// Writes `path` atomically: this file line for line, each vertex whose
  /// position differs (in any bit) from the file's with the new x y z, each
  /// recomputed normal with its new one; byte-identical to write_garment_obj
  /// for the same positions and normals. Throws refit::Error naming `path` (a
  /// non-finite position, an I/O failure) or the source (it changed).
  void write(const std::string& path, const ObjEdits& edits) const;

 private:
  std::string file_;
  std::size_t bytes_ = 0, group_bytes_ = 0;
  std::size_t vertices_ = 0, normals_ = 0, texcoords_ = 0, faces_ = 0;
  bool crlf_ = false;
  // Chunk c: bytes [chunk_begin_[c], chunk_begin_[c+1]); counts before it.
  std::vector<std::size_t> chunk_begin_, first_vertex_, first_texcoord_, first_normal_, first_line_;
  std::vector<std::size_t> group_first_chunk_;  // group g: chunks [group_first_chunk_[g], [g+1])
};

}  // namespace refit
