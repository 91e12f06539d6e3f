// SPDX-License-Identifier: MIT
// How far a triangle reaches across tile borders: what a tile's halo must cover.
#pragma once

#include <algorithm>
#include <array>

#include "citymesh/core/vec.h"

namespace citymesh {

/// The largest x-y distance from the triangle's centroid to one of its corners, squared: a
/// triangle owned by the tile holding its centroid reaches this far into its neighbours
/// (TilingStats::largest_radius; `simulate` sizes its configs' halo by it).
inline double horizontal_reach_squared(const std::array<Vec3d, 3>& corners) {
  const Vec3d centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
  double largest = 0;
  for (const Vec3d& p : corners) {
    const double dx = p.x - centroid.x, dy = p.y - centroid.y;
    largest = std::max(largest, dx * dx + dy * dy);
  }
  return largest;
}

}  // namespace citymesh
