// SPDX-License-Identifier: MIT
// The only source that includes Embree.
#include "citymesh/spatial/ray_scene.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <cstring>

#include "citymesh/core/error.h"

namespace citymesh {

struct RayScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Impl() {
    if (scene != nullptr) rtcReleaseScene(scene);
    if (device != nullptr) rtcReleaseDevice(device);
  }
};

namespace {
void check(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE) throw ProcessingError(fmt::format("ray scene: {} failed (Embree error {})", what, int(e)));
}
}  // namespace

RayScene::RayScene(std::span<const Vec3f> vertices, std::span<const Triangle> triangles)
    : impl_(std::make_unique<Impl>()) {
  impl_->device = rtcNewDevice("verbose=0");
  if (impl_->device == nullptr) throw ProcessingError("ray scene: cannot create an Embree device");
  impl_->scene = rtcNewScene(impl_->device);
  // Robust traversal: no missed hits on shared edges, and results independent of build order.
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), vertices.size()));
  auto* t = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                3 * sizeof(std::uint32_t), triangles.size()));
  check(impl_->device, "buffer allocation");
  std::memcpy(v, vertices.data(), vertices.size_bytes());
  std::memcpy(t, triangles.data(), triangles.size_bytes());
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(impl_->scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(impl_->scene);
  check(impl_->device, "scene build");
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
  rtcIntersect1(impl_->scene, &context, &rh);
  RayHit hit;
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    hit.hit = true;
    hit.distance = rh.ray.tfar;
    hit.triangle = rh.hit.primID;
  }
  return hit;
}

}  // namespace citymesh
