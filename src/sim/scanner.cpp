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
      !(std::abs(p.tilt_deg) < 60) || p.rings < 2 || p.rings > 256 || p.columns < 16 || p.columns > 8192 ||
      !(p.vertical_fov_deg > 1 && p.vertical_fov_deg < 180) || !(p.rotation_rate > 0.01f && p.rotation_rate <= 50)) {
    throw ConfigError("simulate: scanner parameters out of range (line rate 0..1000 Hz, angular step 0.05..10°, "
                      "max range 1..1000 m, noise 0..1 m, |tilt| < 60°; spinning: 2..256 rings, 16..8192 columns, "
                      "field of view 1..180°, 0.01..50 turns/s)");
  }
}

std::size_t line_count(const Scene& scene, const EpochDrive& drive, const ScannerParams& p) {
  return static_cast<std::size_t>(std::floor(scene.length / (drive.speed / p.line_rate))) + 1;
}

std::size_t pulse_count(const ScannerParams& p) {
  return static_cast<std::size_t>(std::lround(360.0f / p.angular_step_deg));
}


std::size_t turn_count(const Scene& scene, const EpochDrive& drive, const ScannerParams& p) {
  return static_cast<std::size_t>(std::floor(scene.length / drive.speed * p.rotation_rate)) + 1;
}

/// Writes one measured return into its cell.
void record(SensorGrid& grid, std::size_t cell, const Vec3f& sensor, const Vec3f& dir, const RayHit& hit,
            double noise, double time, const EpochDrive& drive, std::uint32_t label) {
  const float r = hit.distance + static_cast<float>(noise);
  grid.points[cell] = sensor + dir * r + drive.registration_error;
  grid.sensors[cell] = sensor + drive.registration_error;
  grid.times[cell] = time;
  grid.valid[cell] = 1;
  grid.labels[cell] = label;
}

/// One turn of the spinning sensor: rings x columns, the vehicle moving during the turn.
SensorGrid scan_turn(const Scene& scene, std::size_t epoch, std::size_t turn, const RayScene& rays,
                     const Geometry& geometry, const ScannerParams& p) {
  const EpochDrive& drive = scene.epochs[epoch];
  SensorGrid grid;
  grid.resize(static_cast<std::size_t>(p.rings), static_cast<std::size_t>(p.columns), true);
  grid.origin = scene.origin;
  grid.wrap_columns = true;
  const float fov = p.vertical_fov_deg * float(M_PI) / 180.0f;
  for (std::size_t col = 0; col < grid.cols; ++col) {
    sim::Rng rng(p.seed * 0x100000001B3ull ^ (epoch << 40) ^ (turn << 20) ^ col);
    const double t = (static_cast<double>(turn) + static_cast<double>(col) / static_cast<double>(grid.cols)) /
                     static_cast<double>(p.rotation_rate);
    const Vec3f sensor{drive.speed * static_cast<float>(t), drive.lane_offset, p.sensor_height};
    const float azimuth = 2.0f * float(M_PI) * static_cast<float>(col) / static_cast<float>(grid.cols);
    for (std::size_t ring = 0; ring < grid.rows; ++ring) {
      const float elevation = -fov / 2 + fov * static_cast<float>(ring) / static_cast<float>(std::max(1, p.rings - 1));
      const Vec3f dir{std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
      const RayHit hit = rays.intersect(sensor, dir, p.max_range);
      const double noise = rng.normal() * p.range_noise;
      if (hit.hit) record(grid, grid.index(ring, col), sensor, dir, hit, noise, t, drive, geometry.object_of[hit.triangle]);
    }
  }
  return grid;
}

std::vector<SensorGrid> scan_spinning(const Scene& scene, std::size_t epoch, const ScannerParams& p) {
  const EpochDrive& drive = scene.epochs.at(epoch);
  const Geometry geometry = present_geometry(scene, drive.date);
  const RayScene rays(geometry.vertices, geometry.triangles);
  std::vector<SensorGrid> turns(turn_count(scene, drive, p));
  parallel_for_blocks(turns.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t turn = begin; turn < end; ++turn) turns[turn] = scan_turn(scene, epoch, turn, rays, geometry, p);
  });
  return turns;
}

SensorGrid scan_profiler(const Scene& scene, std::size_t epoch, const ScannerParams& p) {
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
        const double time = (static_cast<double>(line) + static_cast<double>(pulse) / static_cast<double>(pulses)) /
                            static_cast<double>(p.line_rate);
        record(grid, grid.index(line, pulse), sensor, dir, hit, noise, time, drive, geometry.object_of[hit.triangle]);
      }
    }
  });
  return grid;
}

}  // namespace

std::uint64_t rays_per_epoch(const Scene& scene, std::size_t epoch, const ScannerParams& p) {
  const EpochDrive& drive = scene.epochs.at(epoch);
  if (p.mode == ScannerParams::Mode::spinning) {
    return turn_count(scene, drive, p) * static_cast<std::uint64_t>(p.rings) * static_cast<std::uint64_t>(p.columns);
  }
  return line_count(scene, drive, p) * pulse_count(p);
}

std::vector<SensorGrid> scan_epoch(const Scene& scene, std::size_t epoch, const ScannerParams& p) {
  check(p);
  if (p.mode == ScannerParams::Mode::spinning) return scan_spinning(scene, epoch, p);
  std::vector<SensorGrid> grids;
  grids.push_back(scan_profiler(scene, epoch, p));
  return grids;
}

}  // namespace citymesh

namespace citymesh {

namespace {
constexpr float kMinSurfaceCosine = 0.866f;  // 30 degrees
}  // namespace

std::vector<std::uint32_t> surface_labels(const Scene& scene, std::size_t epoch, const Mesh& mesh, float tolerance) {
  const Geometry geometry = present_geometry(scene, scene.epochs.at(epoch).date);
  const RayScene rays(geometry.vertices, geometry.triangles);
  const Vec3f shift(mesh.origin - scene.origin);  // mesh frame -> scene frame
  std::vector<std::uint32_t> labels(mesh.triangle_count(), kNoSurface);
  parallel_for_blocks(labels.size(), 8192, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const Triangle& tri = mesh.triangles[t];
      const Vec3f a = mesh.positions[tri[0]], b = mesh.positions[tri[1]], c = mesh.positions[tri[2]];
      Vec3f n = cross(b - a, c - a);
      const float len = norm(n);
      if (!(len > 0)) continue;
      n = n / len;
      const Vec3f centre = (a + b + c) / 3.0f + shift;
      const RayHit up = rays.intersect(centre, n, tolerance), down = rays.intersect(centre, n * -1.0f, tolerance);
      if (!up.hit && !down.hit) continue;
      const std::uint32_t hit = (up.hit && (!down.hit || up.distance <= down.distance)) ? up.triangle : down.triangle;
      // On the surface only when also parallel to it: a face bridging a depth jump may pass
      // close to a surface at a steep angle.
      const Triangle& s = geometry.triangles[hit];
      const Vec3f& p = geometry.vertices[s[0]];
      const Vec3f m = cross(geometry.vertices[s[1]] - p, geometry.vertices[s[2]] - p);
      if (std::abs(dot(m, n)) >= kMinSurfaceCosine * norm(m)) labels[t] = geometry.object_of[hit];
    }
  });
  return labels;
}

}  // namespace citymesh
