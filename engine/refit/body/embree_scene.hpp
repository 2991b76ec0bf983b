#pragma once
// Triangle meshes in Embree 3 scenes: the one place that copies positions and
// corners into Embree's buffers (the body's surface, the layers of a garment,
// the renderer's pictures).
#include <refit/core/types.hpp>

#include <embree3/rtcore.h>

#include <array>
#include <span>
#include <string>

namespace refit {

/// Adds a triangle geometry to `scene`: every row of `vertices` as floats (a
/// non-finite row as the origin: only triangles that use it see it) and
/// `triangles`, rows of `vertices`. Throws refit::Error "`what`: Embree could
/// not allocate ..." when Embree cannot hold them.
void add_triangles(RTCDevice device, RTCScene scene, const Points& vertices,
                   std::span<const std::array<Index, 3>> triangles, const std::string& what);

/// Builds `scene`; throws refit::Error "`what`: Embree could not build the scene" on an Embree error.
void commit_scene(RTCDevice device, RTCScene scene, const std::string& what);

/// An Embree scene owned (released with it), built at `quality` with `flags`.
class EmbreeScene {
 public:
  EmbreeScene(RTCDevice device, RTCBuildQuality quality, RTCSceneFlags flags = RTC_SCENE_FLAG_NONE);
  ~EmbreeScene() { rtcReleaseScene(scene_); }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  void add_triangles(const Points& vertices, std::span<const std::array<Index, 3>> triangles, const std::string& what) {
    refit::add_triangles(device_, scene_, vertices, triangles, what);
  }
  void commit(const std::string& what) { commit_scene(device_, scene_, what); }
  RTCScene get() const { return scene_; }

 private:
  RTCDevice device_;
  RTCScene scene_;
};

}  // namespace refit
