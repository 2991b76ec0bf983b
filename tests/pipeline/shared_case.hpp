#pragma once
// The shared data (../shared/data) as the quality suite reads it, for the
// pipeline's tests on real garments: a garment on its body A, body A, the
// suite's feature file for it, and the target bodies.
#include "support/test_support.hpp"

#include <refit/core/garment.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace refit::test {

struct SharedCase {
  std::string data;                        // the shared data folder
  std::shared_ptr<const Garment> garment;  // garments/<name>_on_<body A>.obj
  BodyMesh body_a;
  std::vector<FeatureSpec> features;       // bench/quality/features/<name>.json (none for the soup)
  /// bodies/<name>.obj of the shared data.
  BodyMesh body(const std::string& name) const { return read_body(data + "/bodies/" + name + ".obj"); }
};

/// The quality suite's feature file for a shared garment.
inline std::vector<FeatureSpec> suite_features(const std::string& garment) {
  return read_feature_file(std::string(REFIT_SOURCE_DIR) + "/bench/quality/features/" + garment + ".json");
}

/// Shared garment `name` ("skirt", "dress", "jeans", "outfit_dress_jeans" or
/// "dress_soup" on A_female, "male_suit" on M_ref); nothing when the shared
/// data is absent (the test then skips, saying so).
inline std::optional<SharedCase> shared_case(const std::string& name) {
  const std::string data = shared_data_dir();
  if (data.empty()) return std::nullopt;
  const std::string body_a = name == "male_suit" ? "M_ref" : "A_female";
  SharedCase c{data, std::make_shared<const Garment>(read_garment_obj(data + "/garments/" + name + "_on_" + body_a + ".obj")),
               read_body(data + "/bodies/" + body_a + ".obj"), {}};
  if (name != "dress_soup") c.features = suite_features(name);
  return c;
}

}  // namespace refit::test
