// SPDX-License-Identifier: MIT
// Which voxels a box touches, for voxels of one size: the one rounding that the occupancy
// grid's marks and queries and the voxel mask all share, so that a box that overlaps a marked
// box always meets one of its voxels.
#pragma once

#include <array>
#include <cstdint>

#include "citymesh/core/vec.h"

namespace citymesh {

/// Voxels lo..hi on each axis, both included. Voxel i covers [i, i + 1) voxel sizes.
struct VoxelBox {
  std::array<std::int32_t, 3> lo{}, hi{};
  friend bool operator==(const VoxelBox&, const VoxelBox&) = default;
};

/// floor(v) as an integer, without the libm call std::floor makes on plain x86-64 (the grids
/// spent a tenth of their time there).
[[gnu::always_inline]] inline std::int32_t floor_to_int(double v) {
  const auto i = static_cast<std::int32_t>(v);
  return static_cast<double>(i) > v ? i - 1 : i;
}

/// The voxels the closed box [lo, hi] touches, for voxels of 1 / inverse_size metres. Always
/// inlined: returned from a call, the ints were stored in halves and reloaded whole (a
/// store-forwarding stall that took 8 % of the change step).
[[gnu::always_inline]] inline VoxelBox voxel_box(const Vec3f& lo, const Vec3f& hi, double inverse_size) {
  return {{floor_to_int(lo.x * inverse_size), floor_to_int(lo.y * inverse_size), floor_to_int(lo.z * inverse_size)},
          {floor_to_int(hi.x * inverse_size), floor_to_int(hi.y * inverse_size), floor_to_int(hi.z * inverse_size)}};
}

}  // namespace citymesh
