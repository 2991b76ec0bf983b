#pragma once
// The command line's test case: a small procedural body pair, dress and feature
// file written to a temporary folder.
#include "mannequin/mannequin.hpp"
#include "support/test_support.hpp"

#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace refit::test {

// A small procedural case written to files: bodies A and B (belly, hips), a dress
// and its feature file.
struct Case {
  test::TempDir dir;
  std::string a, b, garment, features;
  Case(std::size_t vertices = 6000, bool two_layers = false) {
    mannequin::BodyParams pa, pb;
    pb.belly = 6;
    pb.hip = 104;
    mannequin::GarmentParams g;
    g.target_vertices = vertices;
    g.two_layers = two_layers;
    a = dir.file("A.obj");
    b = dir.file("B.obj");
    garment = dir.file("dress.obj");
    features = dir.file("features.json");
    write_body_obj(a, mannequin::make_body(pa));
    write_body_obj(b, mannequin::make_body(pb));
    write_garment_obj(garment, mannequin::make_garment(pa, g));
    test::write_text(features, mannequin::dress_features_json(pa, g));
  }
  std::string resize(const std::string& out, const std::string& extra = "") const {
    return "resize --quiet --garment '" + garment + "' --from '" + a + "' --to '" + b + "' --out '" + out + "' " + extra;
  }
};

// Only the named outputs may exist in the folder: no partial or temporary files.
inline std::vector<std::string> files_in(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace refit::test
