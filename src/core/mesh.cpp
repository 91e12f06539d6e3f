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

void append_mesh(const Mesh& from, Mesh& to) {
  const Vec3f shift(from.origin - to.origin);
  const auto base = static_cast<std::uint32_t>(to.positions.size());
  for (std::size_t v = 0; v < from.vertex_count(); ++v) {
    append_vertex(from, static_cast<std::uint32_t>(v), to);
    to.positions.back() += shift;
    if (from.has_sensor_positions()) to.sensor_positions.back() += shift;
  }
  for (std::size_t t = 0; t < from.triangle_count(); ++t) {
    const Triangle& tri = from.triangles[t];
    to.triangles.push_back({tri[0] + base, tri[1] + base, tri[2] + base});
    const std::uint32_t acquisition = t < from.triangle_ids.size() ? from.triangle_ids[t].acquisition : 0;
    to.triangle_ids.push_back({acquisition, 0, to.triangle_ids.size()});
  }
  // An attribute one mesh carries and the other not leaves it short (checked without the
  // triangles: the simulator appends hundreds of turns to one mesh).
  const std::size_t n = to.positions.size();
  check_size(to.sensor_positions.size(), n, "sensor_positions");
  check_size(to.times.size(), n, "times");
  check_size(to.intensities.size(), n, "intensities");
  check_size(to.colors.size(), n, "colors");
}

}  // namespace citymesh
