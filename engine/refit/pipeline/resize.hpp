#pragma once
// The resize pipeline: the paper's three steps, read top to bottom in
// GarmentBinding::resize. Bind once (garment + body A + features), apply to
// any number of bodies B.
#include <refit/body/body_mesh.hpp>
#include <refit/core/garment.hpp>
#include <refit/core/progress.hpp>
#include <refit/warp/warp.hpp>

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

namespace refit {

enum class Stage { Warp, Features, Full };

struct ResizeOptions {
  std::string units = "cm";
  WarpOptions warp;
  Stage stage = Stage::Full;
};

struct ResizeResult {
  Points positions;             // every garment vertex, in file order
  nlohmann::json report;        // stage timings (ms), counts, per-stage details
  std::vector<std::string> warnings;
};

/// What depends only on the garment and body A (and later its features),
/// computed once; `resize` does only what body B changes.
class GarmentBinding {
 public:
  /// Throws refit::Error for an empty garment or a bad body A.
  GarmentBinding(std::shared_ptr<const Garment> garment, BodyMesh body_a, ResizeOptions options = {},
                 const Progress& progress = Progress(true));

  /// Resizes the garment to body B (same connectivity as A, else refit::Error).
  ResizeResult resize(const BodyMesh& body_b, const Progress& progress = Progress(true)) const;

  const Garment& garment() const { return *garment_; }
  const ReferenceBody& body_a() const { return body_a_; }
  double bind_ms() const { return bind_ms_; }

 private:
  std::shared_ptr<const Garment> garment_;
  ResizeOptions options_;
  ReferenceBody body_a_;
  WarpBinding warp_;
  double bind_ms_ = 0.0;
};

/// The report's fixed part: version and garment counts.
nlohmann::json garment_summary(const Garment& g);

inline constexpr const char* kVersion = "0.1.0";

}  // namespace refit
