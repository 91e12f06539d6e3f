// SPDX-License-Identifier: MIT
// Mesh invariants and small geometric helpers.
#include "citymesh/core/mesh.h"

#include <fmt/format.h>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {
void check_size(std::size_t actual, std::size_t expected, const char* what) {
  if (actual != 0 && actual != expected) {
    throw ProcessingError(fmt::format("mesh: {} has {} values for {} vertices", what, actual, expected));
  }
}
}  // namespace

void Mesh::check_invariants() const {
  const std::size_t n = positions.size();
  check_size(sensor_positions.size(), n, "sensor_positions");
  check_size(times.size(), n, "times");
  check_size(intensities.size(), n, "intensities");
  check_size(colors.size(), n, "colors");
  if (triangle_ids.size() != triangles.size()) {
    throw ProcessingError(fmt::format("mesh: {} triangle ids for {} triangles", triangle_ids.size(),
                                      triangles.size()));
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (std::uint32_t v : triangles[t]) {
      if (v >= n) {
        throw ProcessingError(fmt::format("mesh: triangle {} uses vertex {} of {}", t, v, n));
      }
    }
  }
}

double doubled_area(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return norm(cross(b - a, c - a));
}

}  // namespace citymesh
