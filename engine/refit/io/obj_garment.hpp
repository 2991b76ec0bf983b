#pragma once
// Garment OBJ files: a fast reader for everything CAD tools put in them (faces
// of any size, `l` polylines, `p` points, UVs, normals, groups, materials,
// vertex colours, unknown statements) and a writer that gives the file back line
// for line with only the positions (and the normals that follow from them)
// changed. Positions stay in the file's units; both run in parallel inside. Bad input: refit::Error naming file and line.
#include <refit/core/garment.hpp>
#include <refit/io/file_bytes.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace refit {

/// What a writer needs to give an OBJ file back line for line: the original text
/// and where in it the numbers that change live.
struct ObjSource {
  /// Byte range [begin, end) inside `text` of the "x y z" of one `v` line or of
  /// one `vn` line (the rest of the line, e.g. vertex colours, is outside it).
  struct Span {
    std::size_t begin = 0, end = 0;
  };
  static constexpr Index kNoNormal = 0xffffffffu;

  std::string file;                  // path it was read from (for messages)
  TextBytes text;                    // the whole file, byte for byte (empty when released: see SourceText)
  std::size_t text_size = 0;         // the file's size in bytes
  /// With the text released: each chunk's std::hash, taken when it was read, so a
  /// writer reading the chunk again knows the file is the one parsed.
  std::vector<std::size_t> chunk_hash;
  bool released() const { return text.size() == 0 && text_size > 0; }
  std::vector<Span> vertex_spans;    // one per `v` line, in file order
  std::vector<Span> normal_spans;    // one per `vn` line, in file order
  Points positions;                  // the `v` values as read (vertices x 3)
  Points normals;                    // the `vn` values as read (normals x 3)
  /// Normal index of every face corner, aligned with Garment::faces.indices
  /// (kNoNormal where the corner has none); empty when no corner has one.
  std::vector<Index> corner_normals;
  std::size_t face_corner_count = 0;  // faces.indices.size() when read
  /// Parsing is done in chunks of whole lines: chunk c covers
  /// text[chunk_begin[c], chunk_begin[c+1]) and its first `v`/`vn` line is
  /// vertex_spans[chunk_first_vertex[c]] / normal_spans[chunk_first_normal[c]].
  std::vector<std::size_t> chunk_begin, chunk_first_vertex, chunk_first_normal;
  bool crlf = false;                  // the file uses CRLF line endings
  std::size_t texcoords = 0;          // number of `vt` lines
  std::vector<std::string> warnings;  // e.g. unknown statements kept verbatim
};

/// What a garment read from a file keeps of the file's text for writing it back.
enum class SourceText {
  kept,      // all of it, in memory (its size in bytes: 144 MB for a 1M-vertex garment)
  released,  // none: a writer reads each chunk again from the file, checked against a
             // hash of it taken when it was read (a file changed since: an error
             // naming it, nothing written). The resize command's choice: that memory
             // was the largest single part of a dense garment's peak.
};

/// Reads a garment OBJ (see parse_garment_obj). Throws refit::Error when the file
/// cannot be read or is malformed.
Garment read_garment_obj(const std::string& path, SourceText text = SourceText::kept);

/// The source's text: its own, or, released, the file read again whole into
/// `store` and checked chunk by chunk. Throws refit::Error naming the file when it
/// cannot be read or has changed since it was parsed.
std::string_view source_text(const ObjSource& source, TextBytes& store);

/// Parses OBJ text: `v x y z [w | r g b]`, `vt`, `vn`, `f` (any size >= 3, every
/// index form v, v/vt, v//vn, v/vt/vn, negative = relative), `l` (>= 2 vertices,
/// v or v/vt), `p` (>= 1 vertex), `g`, `o`, `s`, `usemtl`, `mtllib`, comments,
/// blank lines, CRLF; unknown statements are kept verbatim with a warning. The
/// result's `source` keeps the text for write_garment_obj. Parsed in parallel
/// over chunks of lines; the result does not depend on the thread count.
/// Throws refit::Error "file:line: problem" for a malformed number or
/// statement, an index out of range or 0, a NaN/inf coordinate, a face with
/// fewer than 3 vertices, and "file: empty garment" when there is no vertex.
Garment parse_garment_obj(std::string_view text, const std::string& file_for_errors);

struct ObjWriteReport {
  std::size_t normals_recomputed = 0;
  std::vector<std::string> warnings;
};

/// Writes `g` atomically to `path` (nothing is written when formatting fails).
/// Throws refit::Error naming `path` on non-finite positions, a garment that no
/// longer matches its source, or an I/O failure.
ObjWriteReport write_garment_obj(const std::string& path, const Garment& g);
/// The same for g's elements and source with other `positions` (same rows; a
/// resize result), without copying the garment.
ObjWriteReport write_garment_obj(const std::string& path, const Garment& g, const Points& positions);

/// The OBJ text of `g`. With g.source: the source text where only the x y z of
/// `v` lines change and each referenced `vn` becomes the normalised sum of the
/// area-weighted normals of the faces whose corners use it; everything else is
/// byte-identical; a vertex whose position did not change keeps its original
/// text, and when no position changed the normals are left as they were too, so
/// an unchanged garment is written back byte for byte. Without: a plain OBJ of
/// v, f, l, p lines. Numbers use the
/// shortest round-trip form (std::to_chars). Throws refit::Error on a
/// non-finite position or when the garment's vertex or face-corner count differs
/// from its source.
std::string format_garment_obj(const Garment& g, ObjWriteReport* report = nullptr);

}  // namespace refit
