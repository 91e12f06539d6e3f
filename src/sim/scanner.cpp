// SPDX-License-Identifier: MIT
#include "citymesh/sim/scanner.h"

#include <fmt/format.h>

#include <cmath>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "citymesh/spatial/ray_scene.h"
#include "rng.h"

namespace citymesh {

namespace {

struct Geometry {
  std::vector<Vec3f> vertices;
  std::vector<Triangle> triangles;
  std::vector<std::uint32_t> object_of;  ///< per triangle
};

Geometry present_geometry(const Scene& scene, TimePoint date) {
  Geometry g;
  for (const SceneObject& o : scene.objects) {
    if (!o.present_at(date)) continue;
    const auto base = static_cast<std::uint32_t>(g.vertices.size());
    g.vertices.insert(g.vertices.end(), o.vertices.begin(), o.vertices.end());
    for (const Triangle& t : o.triangles) {
      g.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
      g.object_of.push_back(o.id);
    }
  }
  return g;
}

void check(const ScannerParams& p) {
  if (!(p.line_rate > 0 && p.line_rate <= 1000) || !(p.angular_step_deg >= 0.05f && p.angular_step_deg <= 10) ||
      !(p.max_range > 1 && p.max_range <= 1000) || !(p.range_noise >= 0 && p.range_noise < 1) ||
      !(std::abs(p.tilt_deg) < 60)) {
    throw ConfigError("simulate: scanner parameters out of range (line rate 0..1000 Hz, angular step 0.05..10°, "
                      "max range 1..1000 m, noise 0..1 m, |tilt| < 60°)");
  }
}

std::size_t line_count(const Scene& scene, const EpochDrive& drive, const ScannerParams& p) {
  return static_cast<std::size_t>(std::floor(scene.length / (drive.speed / p.line_rate))) + 1;
}

std::size_t pulse_count(const ScannerParams& p) {
  return static_cast<std::size_t>(std::lround(360.0f / p.angular_step_deg));
}

}  // namespace

std::uint64_t rays_per_epoch(const Scene& scene, std::size_t epoch, const ScannerParams& params) {
  return line_count(scene, scene.epochs.at(epoch), params) * pulse_count(params);
}

SensorGrid scan_epoch(const Scene& scene, std::size_t epoch, const ScannerParams& p) {
  check(p);
  const EpochDrive& drive = scene.epochs.at(epoch);
  const Geometry geometry = present_geometry(scene, drive.date);
  const RayScene rays(geometry.vertices, geometry.triangles);
  const std::size_t lines = line_count(scene, drive, p), pulses = pulse_count(p);
  SensorGrid grid;
  grid.resize(lines, pulses, true);
  grid.origin = scene.origin;
  grid.wrap_columns = true;  // a full turn: the last pulse of a line neighbours the first
  const float step = p.angular_step_deg * float(M_PI) / 180.0f, tilt = p.tilt_deg * float(M_PI) / 180.0f;
  const float spacing = drive.speed / p.line_rate;
  parallel_for_blocks(lines, 8, [&](std::size_t begin, std::size_t end) {
    for (std::size_t line = begin; line < end; ++line) {
      // One generator per line: the noise does not depend on which thread scans the line.
      sim::Rng rng(p.seed * 0x100000001B3ull ^ (epoch << 40) ^ line);
      const Vec3f sensor{static_cast<float>(line) * spacing, drive.lane_offset, p.sensor_height};
      for (std::size_t pulse = 0; pulse < pulses; ++pulse) {
        const float theta = -float(M_PI) / 2 + static_cast<float>(pulse) * step;  // starts straight down
        const Vec3f dir{-std::cos(theta) * std::sin(tilt), std::cos(theta) * std::cos(tilt), std::sin(theta)};
        const RayHit hit = rays.intersect(sensor, dir, p.max_range);
        const double noise = rng.normal() * p.range_noise;
        if (!hit.hit) continue;
        const std::size_t cell = grid.index(line, pulse);
        const float r = hit.distance + static_cast<float>(noise);
        grid.points[cell] = sensor + dir * r + drive.registration_error;
        grid.sensors[cell] = sensor + drive.registration_error;
        grid.times[cell] = (static_cast<double>(line) + static_cast<double>(pulse) / static_cast<double>(pulses)) /
                           static_cast<double>(p.line_rate);
        grid.valid[cell] = 1;
        grid.labels[cell] = geometry.object_of[hit.triangle];
      }
    }
  });
  return grid;
}

}  // namespace citymesh
