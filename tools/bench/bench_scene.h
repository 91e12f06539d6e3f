// SPDX-License-Identifier: MIT
// The simulated street the change and mosaic benchmarks share (about 300 k triangles over 7
// epochs at the defaults, the size of the paper's Robotcar experiment).
#pragma once

#include <cstdint>
#include <vector>

#include "citymesh/core/mesh.h"
#include "citymesh/core/time.h"
#include "citymesh/scan/sensor_grid.h"
#include "citymesh/sim/scanner.h"
#include "citymesh/sim/scene.h"

namespace citymesh::bench {

struct BenchScene {
  std::vector<Mesh> meshes;  ///< one per epoch, common origin
  std::vector<TimePoint> dates;
  std::size_t triangles = 0;
};

inline BenchScene simulated_street(float length, int epochs) {
  StreetParams street;
  street.length = length;
  street.epochs = epochs;
  const Scene scene = make_street_scene(street);
  BenchScene out;
  for (std::size_t k = 0; k < scene.epochs.size(); ++k) {
    Mesh m = mesh_sensor_grid(scan_epoch(scene, k, {}).front(), {}, static_cast<std::uint32_t>(k)).mesh;
    m.origin = out.meshes.empty() ? m.origin : out.meshes.front().origin;
    out.triangles += m.triangle_count();
    out.meshes.push_back(std::move(m));
    out.dates.push_back(scene.epochs[k].date);
  }
  return out;
}

}  // namespace citymesh::bench
