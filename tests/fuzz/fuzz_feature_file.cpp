// libFuzzer target: the feature file parser on arbitrary bytes, then sampling the
// accepted features on a small procedural dress (what `refit resize --features`
// does next).
#include <mannequin/mannequin.hpp>
#include <refit/core/error.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/features/feature_file.hpp>

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const refit::Garment dress = [] {
    refit::mannequin::GarmentParams gp;
    gp.kind = refit::mannequin::GarmentParams::Kind::Dress;
    gp.target_vertices = 1000;
    return refit::mannequin::make_garment({}, gp);
  }();
  try {
    const auto specs =
        refit::parse_feature_json(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json", "cm");
    refit::build_feature_curves(dress, specs);
  } catch (const refit::Error&) {
  }
  return 0;
}
