// SPDX-License-Identifier: MIT
// Closest-hit ray casting against a static triangle mesh (Embree 3 behind this header). The
// simulator's scanner casts its pulses with it.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>

#include "citymesh/core/mesh.h"

namespace citymesh {

struct RayHit {
  bool hit = false;
  float distance = std::numeric_limits<float>::infinity();  ///< along the unit direction, metres
  std::uint32_t triangle = 0;                                 ///< index into the scene's triangles
};

class RayScene {
 public:
  /// Builds the acceleration structure over `vertices` (local frame) and `triangles` (copied).
  RayScene(std::span<const Vec3f> vertices, std::span<const Triangle> triangles);
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  /// Nearest hit of the ray origin + t * direction, 0 <= t <= max_distance. `direction` must
  /// have unit length. Thread-safe.
  [[nodiscard]] RayHit intersect(const Vec3f& origin, const Vec3f& direction, float max_distance) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace citymesh
