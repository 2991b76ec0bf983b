#include <refit/metrics/render.hpp>
#include <refit/body/embree_ray.hpp>
#include <refit/body/embree_scene.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/atomic_file.hpp>

#include <embree3/rtcore.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wunused-function"
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#include <stb_image_write.h>
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

#include <algorithm>
#include <numeric>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <span>
#include <vector>

namespace refit {

namespace {

struct Camera {
  Vec3 forward, right, up;
};

Camera camera_for(View v) {
  // Bodies face +Z with +Y up: the front view looks along -Z, the side view
  // (the body's left side) along -X, the back view along +Z.
  switch (v) {
    case View::side: return {Vec3(-1, 0, 0), Vec3(0, 0, -1), Vec3(0, 1, 0)};
    case View::back: return {Vec3(0, 0, 1), Vec3(-1, 0, 0), Vec3(0, 1, 0)};
    case View::front: break;
  }
  return {Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(0, 1, 0)};
}

// One Embree scene: the body (geometry 0) and a garment's fan triangles (geometry 1),
// those with finite corners.
class Scene {
 public:
  Scene(RTCDevice device, const BodyMesh& body, const Garment& garment)
      : scene_(device, RTC_BUILD_QUALITY_LOW) {  // one picture: build fast, trace little
    const auto finite = [](const Points& p, std::span<const Index> corners) {
      return std::all_of(corners.begin(), corners.end(), [&](Index i) { return p.row(i).allFinite(); });
    };
    std::vector<std::array<Index, 3>> triangles;
    for (const auto& t : body.triangles)
      if (finite(body.vertices, t)) triangles.push_back(t);
    scene_.add_triangles(body.vertices, triangles, "render");
    triangles.clear();
    for (std::size_t f = 0; f < garment.faces.rows(); ++f) {
      const auto face = garment.faces.row(f);
      for (std::size_t k = 1; k + 1 < face.size(); ++k) {
        const std::array<Index, 3> t{face[0], face[k], face[k + 1]};
        if (finite(garment.positions, t)) triangles.push_back(t);
      }
    }
    scene_.add_triangles(garment.positions, triangles, "render");
    scene_.commit("render");
  }
  RTCScene get() const { return scene_.get(); }

 private:
  EmbreeScene scene_;
};

struct Panel {
  int x0 = 0, width = 0;
  int garment = 0;  // 0 or 1
  Camera camera;
};

// Bounding box of the finite rows.
void grow(Vec3& lo, Vec3& hi, const Points& p) {
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    if (p.row(i).allFinite()) {
      lo = lo.cwiseMin(p.row(i).transpose());
      hi = hi.cwiseMax(p.row(i).transpose());
    }
}

// Text in black with stb_easy_font (a 6-pixel-high stroke font made of quads),
// each font pixel drawn as a scale x scale block; clipped to the image.
void draw_text(Image& img, int x, int y, const std::string& text, int scale) {
  if (text.empty()) return;
  std::vector<char> buffer(text.size() * 270 + 1000);  // stb_easy_font: up to ~270 bytes per character
  std::string copy = text;
  unsigned char black[4] = {0, 0, 0, 255};
  const int quads = stb_easy_font_print(0, 0, copy.data(), black, buffer.data(), static_cast<int>(buffer.size()));
  for (int q = 0; q < quads; ++q) {
    const float* v = reinterpret_cast<const float*>(buffer.data() + static_cast<std::size_t>(q) * 64);
    // Vertices 0 and 2 of a quad are opposite corners (each vertex: x, y, z, colour = 16 bytes).
    const int x0 = x + static_cast<int>(std::lround(v[0] * scale)), y0 = y + static_cast<int>(std::lround(v[1] * scale));
    const int x1 = x + static_cast<int>(std::lround(v[8] * scale)), y1 = y + static_cast<int>(std::lround(v[9] * scale));
    for (int py = std::max(0, y0); py < std::min(img.height, y1); ++py)
      for (int px = std::max(0, x0); px < std::min(img.width, x1); ++px)
        std::fill_n(&img.rgb[(static_cast<std::size_t>(py) * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(px)) * 3], 3,
                    std::uint8_t{0});
  }
}

int text_width(const std::string& text, int scale) {
  std::string copy = text;
  return stb_easy_font_width(copy.data()) * scale;
}

}  // namespace

View parse_view(const std::string& name, const std::string& what) {
  if (name == "front") return View::front;
  if (name == "side") return View::side;
  if (name == "back") return View::back;
  throw Error(what + ": unknown view '" + name + "' (expected front, side or back)");
}

Image render(const BodyMesh& body, const Garment& garment, const Garment* garment2, const std::vector<Points>& curves,
             const RenderOptions& options) {
  if (options.width < 16 || options.height < 16 || options.width > 16384 || options.height > 16384)
    throw Error("render: picture size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                " is out of range (16 to 16384 per side)");
  if (options.views.empty()) throw Error("render: no view requested");
  if (!(options.zoom >= 1.0 && options.zoom <= 1000.0))
    throw Error("render: zoom " + std::to_string(options.zoom) + " is out of range (1 to 1000)");
  if (!(options.centre_x >= 0.0 && options.centre_x <= 1.0 && options.centre_y >= 0.0 && options.centre_y <= 1.0))
    throw Error("render: the zoom's centre must lie within the panel (0 to 1 across and down)");

  std::unique_ptr<RTCDeviceTy, void (*)(RTCDevice)> device(rtcNewDevice(nullptr), rtcReleaseDevice);
  if (!device) throw Error("render: cannot create an Embree device");
  std::vector<std::unique_ptr<Scene>> scenes;
  scenes.push_back(std::make_unique<Scene>(device.get(), body, garment));
  if (garment2) scenes.push_back(std::make_unique<Scene>(device.get(), body, *garment2));

  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  grow(lo, hi, body.vertices);
  grow(lo, hi, garment.positions);
  if (garment2) grow(lo, hi, garment2->positions);
  if (!lo.allFinite()) throw Error("render: nothing finite to draw");
  const Vec3 centre = 0.5 * (lo + hi);
  const double depth = (hi - lo).norm() + 1.0;

  // One scale for every panel (views and garments compare at a glance); each
  // panel is as wide as its view of the box needs, so a front view spread by the
  // arms is not shrunk to the width of a side view.
  std::vector<Panel> panels;
  std::vector<double> across;
  const Vec3 ext = hi - lo;
  for (int g = 0; g < static_cast<int>(scenes.size()); ++g)
    for (View v : options.views) {
      Panel p;
      p.garment = g;
      p.camera = camera_for(v);
      across.push_back(std::abs(ext.dot(p.camera.right)) + 1e-9);
      panels.push_back(p);
    }
  const double total = std::accumulate(across.begin(), across.end(), 0.0);
  double upward = 0.0;
  for (const Panel& p : panels) upward = std::max(upward, std::abs(ext.dot(p.camera.up)));
  // A band at the top for the title and the labels; the bodies are framed below it.
  const int text_scale = std::max(1, options.height / 300);
  const int band = (options.title.empty() ? 0 : 10 * text_scale) + (options.labels.empty() ? 0 : 10 * text_scale) +
                   (options.title.empty() && options.labels.empty() ? 0 : 2 * text_scale);
  const double scale = 1.08 * std::max(total / options.width, upward / std::max(1, options.height - band)) + 1e-12;
  const double middle_y = 0.5 * (options.height + band);  // picture row of the box's centre
  double edge = 0.0;
  for (std::size_t i = 0; i < panels.size(); ++i) {
    panels[i].x0 = static_cast<int>(std::lround(edge / total * options.width));
    edge += across[i];
    panels[i].width = static_cast<int>(std::lround(edge / total * options.width)) - panels[i].x0;
  }
  const std::vector<double> pixel(panels.size(), scale / options.zoom);
  // Where each panel's zoom centre lies from the box's centre (right, up), at zoom 1.
  std::vector<Eigen::Vector2d> shift(panels.size());
  for (std::size_t i = 0; i < panels.size(); ++i)
    shift[i] = Eigen::Vector2d((options.centre_x - 0.5) * panels[i].width * scale,
                               (middle_y - band - options.centre_y * (options.height - band)) * scale);

  Image img;
  img.width = options.width;
  img.height = options.height;
  img.rgb.assign(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 3, kBackground[0]);
  const std::array<Vec3, 3> colour = {Vec3(0.82, 0.74, 0.66), Vec3(0.25, 0.45, 0.85), Vec3(0.85, 0.42, 0.25)};
  const double ambient = 0.18;

  parallel_for(0, static_cast<std::size_t>(img.height), 8, [&](std::size_t y0, std::size_t y1) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (std::size_t y = y0; y < y1; ++y)
      for (std::size_t pi = 0; pi < panels.size(); ++pi) {
        const Panel& p = panels[pi];
        const Camera& c = p.camera;
        for (int x = p.x0; x < p.x0 + p.width; ++x) {
          const double u = (x - p.x0 + 0.5 - 0.5 * p.width) * pixel[pi] + shift[pi].x();
          const double v = (middle_y - (static_cast<double>(y) + 0.5)) * pixel[pi] + shift[pi].y();
          const Vec3 o = centre + u * c.right + v * c.up - depth * c.forward;
          RTCRayHit rh = make_ray(o, c.forward);
          rtcIntersect1(scenes[static_cast<std::size_t>(p.garment)]->get(), &ctx, &rh);
          if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
          Vec3 n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
          const double len = n.norm();
          // Headlight, shaded on both sides: garments are open shells seen from either side.
          const double lambert = len > 0.0 ? std::abs(n.dot(c.forward)) / len : 0.0;
          const Vec3 base = rh.hit.geomID == 0 ? colour[0] : colour[1 + static_cast<std::size_t>(p.garment)];
          const Vec3 rgb = base * (ambient + (1.0 - ambient) * lambert);
          std::uint8_t* px = &img.rgb[(y * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(x)) * 3];
          for (int k = 0; k < 3; ++k) px[k] = static_cast<std::uint8_t>(std::clamp(rgb[k] * 255.0 + 0.5, 0.0, 255.0));
        }
      }
  });

  // Feature curves on top of garment 1's panels: thick red lines, no depth test.
  const double radius = std::max(1.5, options.height / 400.0);
  for (std::size_t pi = 0; pi < panels.size(); ++pi) {
    const Panel& p = panels[pi];
    if (p.garment != 0) continue;
    auto to_pixel = [&](const Vec3& q) {
      const Vec3 d = q - centre;
      return Eigen::Vector2d(p.x0 + 0.5 * p.width + (d.dot(p.camera.right) - shift[pi].x()) / pixel[pi],
                             middle_y - (d.dot(p.camera.up) - shift[pi].y()) / pixel[pi]);
    };
    auto stamp = [&](const Eigen::Vector2d& s) {
      if (s.y() + radius < 0.0 || s.y() - radius >= img.height || s.x() + radius < p.x0 || s.x() - radius >= p.x0 + p.width)
        return;  // off the panel (a zoomed picture shows a small part of each curve)
      for (int y = static_cast<int>(std::floor(s.y() - radius)); y <= static_cast<int>(std::ceil(s.y() + radius)); ++y)
        for (int x = static_cast<int>(std::floor(s.x() - radius)); x <= static_cast<int>(std::ceil(s.x() + radius)); ++x) {
          if (y < 0 || y >= img.height || x < p.x0 || x >= p.x0 + p.width) continue;
          if ((Eigen::Vector2d(x + 0.5, y + 0.5) - s).norm() > radius) continue;
          std::uint8_t* px = &img.rgb[(static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(x)) * 3];
          px[0] = 220;
          px[1] = 20;
          px[2] = 60;
        }
    };
    for (const Points& curve : curves)
      for (Eigen::Index i = 0; i + 1 < curve.rows(); ++i) {
        if (!curve.row(i).allFinite() || !curve.row(i + 1).allFinite()) continue;
        const Eigen::Vector2d a = to_pixel(curve.row(i).transpose()), b = to_pixel(curve.row(i + 1).transpose());
        const int steps = std::min(100000, static_cast<int>(std::ceil((b - a).norm() / 0.5)) + 1);
        for (int s = 0; s <= steps; ++s) stamp(a + (b - a) * (static_cast<double>(s) / steps));
      }
  }

  // Labels: centred over each garment's panels; the title across the top.
  const int line = 10 * text_scale;
  for (std::size_t g = 0; g < scenes.size() && g < options.labels.size(); ++g) {
    int x0 = img.width, x1 = 0;
    for (const Panel& p : panels)
      if (p.garment == static_cast<int>(g)) x0 = std::min(x0, p.x0), x1 = std::max(x1, p.x0 + p.width);
    const int top = options.title.empty() ? text_scale * 2 : text_scale * 2 + line;
    draw_text(img, (x0 + x1 - text_width(options.labels[g], text_scale)) / 2, top, options.labels[g], text_scale);
  }
  draw_text(img, (img.width - text_width(options.title, text_scale)) / 2, text_scale * 2, options.title, text_scale);
  return img;
}

void write_png(const std::string& path, const Image& image) {
  std::string bytes;
  const int ok = stbi_write_png_to_func(
      [](void* context, void* data, int size) { static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<std::size_t>(size)); },
      &bytes, image.width, image.height, 3, image.rgb.data(), image.width * 3);
  if (!ok) throw Error(path + ": could not encode the PNG");
  write_file_atomically(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace refit
