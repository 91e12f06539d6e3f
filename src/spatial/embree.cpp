// SPDX-License-Identifier: MIT
// The only source that includes Embree: ray casting.
#include "citymesh/spatial/ray_scene.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

/// An Embree device and the one scene built on it, released together; errors name `owner`.
struct EmbreeScene {
  const char* owner;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  explicit EmbreeScene(const char* who) : owner(who), device(rtcNewDevice("verbose=0")) {
    if (device == nullptr) throw ProcessingError(fmt::format("{}: cannot create an Embree device", owner));
  }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;
  ~EmbreeScene() {
    if (scene != nullptr) rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
  void check(const char* what) const {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE) throw ProcessingError(fmt::format("{}: {} failed (Embree error {})", owner, what, int(e)));
  }
};

}  // namespace

struct RayScene::Impl {
  EmbreeScene embree{"ray scene"};
};

RayScene::RayScene(std::span<const Vec3f> vertices, std::span<const Triangle> triangles)
    : impl_(std::make_unique<Impl>()) {
  EmbreeScene& e = impl_->embree;
  e.scene = rtcNewScene(e.device);
  // Robust traversal: no missed hits on shared edges, and results independent of build order.
  rtcSetSceneFlags(e.scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry geometry = rtcNewGeometry(e.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), vertices.size()));
  auto* t = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                3 * sizeof(std::uint32_t), triangles.size()));
  e.check("buffer allocation");
  std::memcpy(v, vertices.data(), vertices.size_bytes());
  std::memcpy(t, triangles.data(), triangles.size_bytes());
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(e.scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(e.scene);
  e.check("scene build");
}

RayScene::~RayScene() = default;

RayHit RayScene::intersect(const Vec3f& origin, const Vec3f& direction, float max_distance) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = origin.x;
  rh.ray.org_y = origin.y;
  rh.ray.org_z = origin.z;
  rh.ray.dir_x = direction.x;
  rh.ray.dir_y = direction.y;
  rh.ray.dir_z = direction.z;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = max_distance;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->embree.scene, &context, &rh);
  RayHit hit;
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    hit.hit = true;
    hit.distance = rh.ray.tfar;
    hit.triangle = rh.hit.primID;
  }
  return hit;
}

}  // namespace citymesh
