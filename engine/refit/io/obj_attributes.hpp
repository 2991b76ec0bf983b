#pragma once
// What a garment OBJ says about its faces beyond their vertices: the texture
// coordinates of every face corner and the group (`o` / `g`) every face is in.
// Read on demand from the text a garment keeps (ObjSource), so that a resize,
// which needs neither, does not pay for them in memory.
//
// In: a Garment read by read_garment_obj (its source already validated).
// Out: per face corner a `vt` index (or kNoTexcoord), the `vt` values, and per
// face a group index into group_names. Refuses nothing the reader accepted.
#include <refit/core/garment.hpp>

#include <string>
#include <vector>

namespace refit {

struct ObjFaceAttributes {
  static constexpr Index kNoTexcoord = 0xffffffffu;
  Points texcoords;                     // the `vt` values (u, v, w; missing ones 0), in file order
  std::vector<Index> corner_texcoords;  // aligned with Garment::faces.indices; empty when no corner has a `vt`
  /// Per face, an index into group_names: the `o` and `g` names in force at the
  /// face ("" before any), "object/group" when both are given and differ.
  std::vector<Index> face_groups;
  std::vector<std::string> group_names;  // in order of first use
};

/// The corner texture coordinates and face groups of `g`. A garment without a
/// source (generated) has none: empty vectors, every face in group "".
ObjFaceAttributes obj_face_attributes(const Garment& g);

}  // namespace refit
