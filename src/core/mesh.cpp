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

void Mesh::shrink_to_fit() {
  positions.shrink_to_fit();
  sensor_positions.shrink_to_fit();
  times.shrink_to_fit();
  intensities.shrink_to_fit();
  colors.shrink_to_fit();
  triangles.shrink_to_fit();
  triangle_ids.shrink_to_fit();
}

void append_vertex(const Mesh& from, std::uint32_t v, Mesh& to) {
  to.positions.push_back(from.positions[v]);
  if (!from.sensor_positions.empty()) to.sensor_positions.push_back(from.sensor_positions[v]);
  if (!from.times.empty()) to.times.push_back(from.times[v]);
  if (!from.intensities.empty()) to.intensities.push_back(from.intensities[v]);
  if (!from.colors.empty()) to.colors.push_back(from.colors[v]);
}

}  // namespace citymesh
