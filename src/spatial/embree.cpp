// SPDX-License-Identifier: MIT
// The only source that includes Embree: ray casting and box collision.
#include "citymesh/spatial/ray_scene.h"
#include "citymesh/spatial/box_tree.h"

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

// ---- box tree ------------------------------------------------------------------------

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
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
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

bool overlaps(const Box3f& p, const Box3f& q) {
  return p.min.x <= q.max.x && q.min.x <= p.max.x && p.min.y <= q.max.y && q.min.y <= p.max.y &&
         p.min.z <= q.max.z && q.min.z <= p.max.z;
}

}  // namespace

struct BoxTree::Impl {
  EmbreeScene embree{"box tree"};
  std::vector<Box3f> boxes;
  BoxSet set;
};

namespace {

struct BoxQuery {
  std::span<const Box3f> boxes;
  Box3f query;
  std::vector<std::uint32_t>* out;
};

/// Called by Embree for every box of a leaf whose bounds meet the query's sphere.
bool collect_overlapping(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<BoxQuery*>(args->userPtr);
  if (overlaps(q->boxes[args->primID], q->query)) q->out->push_back(args->primID);
  return false;  // the query radius is unchanged
}

}  // namespace

BoxTree::BoxTree(std::vector<Box3f> boxes) : impl_(std::make_unique<Impl>()) {
  impl_->boxes = std::move(boxes);
  impl_->set.boxes = impl_->boxes;
  EmbreeScene& e = impl_->embree;
  if (!impl_->boxes.empty()) e.scene = box_scene(e.device, impl_->set);
  e.check("build");
}

BoxTree::~BoxTree() = default;

void BoxTree::containing(const Vec3f& p, std::vector<std::uint32_t>& out) const { overlapping({p, p}, out); }

void BoxTree::overlapping(const Box3f& b, std::vector<std::uint32_t>& out) const {
  out.clear();
  if (impl_->embree.scene == nullptr) return;
  // Embree's point queries visit what meets a sphere: the one around the query box, widened
  // by a few float steps of the coordinates for the rounding of its centre.
  const Vec3f centre = (b.min + b.max) * 0.5f;
  const Vec3f half = (b.max - b.min) * 0.5f;
  const float magnitude = std::max({std::abs(centre.x), std::abs(centre.y), std::abs(centre.z)});
  RTCPointQuery query{};
  query.x = centre.x;
  query.y = centre.y;
  query.z = centre.z;
  query.radius = std::sqrt(dot(half, half)) * (1 + 1e-6f) + 1e-6f * magnitude + 1e-7f;
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  BoxQuery q{impl_->boxes, b, &out};
  rtcPointQuery(impl_->embree.scene, &query, &context, collect_overlapping, &q);
}

}  // namespace citymesh
