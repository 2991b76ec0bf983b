// Triangle meshes in Embree 3 scenes (embree_scene.hpp).
#include <refit/body/embree_scene.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include <cmath>

namespace refit {

void add_triangles(RTCDevice device, RTCScene scene, const Points& vertices,
                   std::span<const std::array<Index, 3>> triangles, const std::string& what) {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (!geom) throw Error(what + ": Embree could not make a triangle geometry");
  const std::size_t nv = static_cast<std::size_t>(vertices.rows()), nt = triangles.size();
  // Embree's own buffers are padded for its vector loads.
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), std::max<std::size_t>(nv, 1)));
  auto* ib = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
  if (!vb || (nt > 0 && !ib)) {
    rtcReleaseGeometry(geom);
    throw Error(what + ": Embree could not allocate " + std::to_string(nt) + " triangles on " + std::to_string(nv) +
                " vertices");
  }
  parallel_for(0, nv, 65536, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const bool finite = vertices.row(Eigen::Index(i)).allFinite();
      for (int k = 0; k < 3; ++k)
        vb[3 * i + std::size_t(k)] = finite ? static_cast<float>(vertices(Eigen::Index(i), k)) : 0.0f;
    }
  });
  parallel_for(0, nt, 65536, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t)
      for (std::size_t k = 0; k < 3; ++k) ib[3 * t + k] = triangles[t][k];
  });
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
}

void commit_scene(RTCDevice device, RTCScene scene, const std::string& what) {
  rtcCommitScene(scene);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw Error(what + ": Embree could not build the scene");
}

EmbreeScene::EmbreeScene(RTCDevice device, RTCBuildQuality quality, RTCSceneFlags flags)
    : device_(device), scene_(rtcNewScene(device)) {
  if (!scene_) throw Error("Embree could not make a scene");
  rtcSetSceneFlags(scene_, flags);
  rtcSetSceneBuildQuality(scene_, quality);
}

}  // namespace refit
