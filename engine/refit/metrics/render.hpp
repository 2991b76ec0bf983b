#pragma once
// Headless pictures of a resize: Embree ray casting with an orthographic camera
// framing the body, plain Lambert shading with a headlight (folds and profiles
// show), the body and one or two garments side by side, feature curves drawn on
// top. PNG through stb_image_write. Sizes in pixels; the meshes in any one unit (the camera frames the body).
#include <refit/body/body_mesh.hpp>
#include <refit/core/garment.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace refit {

enum class View { front, side, back };

/// "front", "side" or "back"; throws refit::Error naming `what` otherwise.
View parse_view(const std::string& name, const std::string& what = "--views");

struct RenderOptions {
  int width = 800, height = 1000;       // whole picture, pixels
  std::vector<View> views = {View::front};
  std::vector<std::string> labels;  // written above garment 1's panels, then garment 2's (may be empty)
  std::string title;                // written across the top (may be empty)
  /// Magnification of every panel about its point (centre_x, centre_y): fractions
  /// of the panel's width and of the framed height at zoom 1 (0, 0: top left), so a
  /// detail found on a whole-body picture is framed by where it shows there (a
  /// 0.1 cm fold of a dense garment is a pixel at 1000 pixels a body).
  double zoom = 1.0;
  double centre_x = 0.5, centre_y = 0.5;
};

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, top row first, 3 bytes per pixel
};

/// One panel per (garment, view): garment 1's panels on the left half, garment 2's
/// (when given) on the right. Each panel shows the body and that garment; every
/// polyline in `curves` is drawn on top of garment 1's panels as a thick line.
/// `options.labels` and `options.title` are written in black on the background.
/// Throws refit::Error for a size below 16x16 or above 16384 per side, no view, a
/// zoom below 1 or above 1000, or a centre outside the panel (0 to 1).
Image render(const BodyMesh& body, const Garment& garment, const Garment* garment2,
             const std::vector<Points>& curves, const RenderOptions& options);

/// Writes `image` as PNG, atomically. Throws refit::Error naming `path` on failure.
void write_png(const std::string& path, const Image& image);

/// The background colour (for tests and callers that look for content).
inline constexpr std::uint8_t kBackground[3] = {255, 255, 255};

}  // namespace refit
