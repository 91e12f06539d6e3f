// SPDX-License-Identifier: MIT
// The only source that includes Embree: ray casting and box collision.
#include "citymesh/spatial/ray_scene.h"
#include "citymesh/spatial/box_collide.h"

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

// ---- box collision ------------------------------------------------------------------------

namespace citymesh {

namespace {

struct BoxSet {
  std::span<const Box3f> boxes;
};

void box_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* set = static_cast<const BoxSet*>(args->geometryUserPtr);
  const Box3f& b = set->boxes[args->primID];
  args->bounds_o->lower_x = b.min.x;
  args->bounds_o->lower_y = b.min.y;
  args->bounds_o->lower_z = b.min.z;
  args->bounds_o->upper_x = b.max.x;
  args->bounds_o->upper_y = b.max.y;
  args->bounds_o->upper_z = b.max.z;
}

/// A scene of one user geometry whose primitives are the boxes.
RTCScene box_scene(RTCDevice device, BoxSet& set) {
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(set.boxes.size()));
  rtcSetGeometryUserData(geometry, &set);
  rtcSetGeometryBoundsFunction(geometry, box_bounds, nullptr);
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  return scene;
}

struct CollideContext {
  const std::function<void(std::span<const BoxPair>)>* on_pairs;
  std::span<const Box3f> a, b;
};

bool overlaps(const Box3f& p, const Box3f& q) {
  return p.min.x <= q.max.x && q.min.x <= p.max.x && p.min.y <= q.max.y && q.min.y <= p.max.y &&
         p.min.z <= q.max.z && q.min.z <= p.max.z;
}

void on_collisions(void* user, RTCCollision* collisions, unsigned count) {
  const auto* ctx = static_cast<const CollideContext*>(user);
  // Embree reports leaf pairs whose node bounds overlap; keep the pairs whose own boxes do.
  BoxPair batch[256];
  std::size_t n = 0;
  for (unsigned i = 0; i < count; ++i) {
    const BoxPair p{collisions[i].primID0, collisions[i].primID1};
    if (!overlaps(ctx->a[p.a], ctx->b[p.b])) continue;
    batch[n++] = p;
    if (n == std::size(batch)) {
      (*ctx->on_pairs)(std::span<const BoxPair>(batch, n));
      n = 0;
    }
  }
  if (n > 0) (*ctx->on_pairs)(std::span<const BoxPair>(batch, n));
}

}  // namespace

void collide_boxes(std::span<const Box3f> a, std::span<const Box3f> b,
                   const std::function<void(std::span<const BoxPair>)>& on_pairs) {
  if (a.empty() || b.empty()) return;
  RTCDevice device = rtcNewDevice("verbose=0");
  if (device == nullptr) throw ProcessingError("box collision: cannot create an Embree device");
  BoxSet set_a{a}, set_b{b};
  RTCScene scene_a = box_scene(device, set_a);
  RTCScene scene_b = box_scene(device, set_b);
  CollideContext ctx{&on_pairs, a, b};
  rtcCollide(scene_a, scene_b, on_collisions, &ctx);
  const RTCError e = rtcGetDeviceError(device);
  rtcReleaseScene(scene_a);
  rtcReleaseScene(scene_b);
  rtcReleaseDevice(device);
  if (e != RTC_ERROR_NONE) throw ProcessingError(fmt::format("box collision failed (Embree error {})", int(e)));
}

}  // namespace citymesh
