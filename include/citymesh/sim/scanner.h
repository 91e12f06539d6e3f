// SPDX-License-Identifier: MIT
// A simulated mobile 2D profiler: a vehicle drives along the street and sweeps a scan plane
// perpendicular to its track, casting one ray per pulse through Embree.
#pragma once

#include <cstdint>

#include "citymesh/scan/sensor_grid.h"
#include "citymesh/sim/scene.h"

namespace citymesh {

struct ScannerParams {
  /// profiler: a 2D scan plane swept along the track (Riegl-like); spinning: a multi-beam
  /// sensor turning about the vertical (Ouster/Velodyne-like), one grid per turn.
  enum class Mode { profiler, spinning };
  Mode mode = Mode::profiler;
  float line_rate = 25.0f;        ///< scan lines per second
  float angular_step_deg = 1.5f;  ///< between successive pulses of a line
  float max_range = 60.0f;        ///< metres
  float range_noise = 0.005f;     ///< metres, standard deviation of the Gaussian range error
  float sensor_height = 2.5f;     ///< metres above the road
  float tilt_deg = 0.0f;          ///< rotation of the scan plane about the vertical
  std::uint64_t seed = 1;         ///< noise seed (combined with the epoch and line)
  // spinning mode
  int rings = 32;                   ///< beams, spread evenly over the vertical field of view
  float vertical_fov_deg = 40.0f;   ///< from -fov/2 to +fov/2 around the horizontal
  int columns = 1024;               ///< azimuth steps per turn
  float rotation_rate = 2.0f;       ///< turns per second
};

/// Scans epoch `epoch` of `scene`: the objects present at its date, driven as its EpochDrive
/// says, from x = 0 to x = scene.length. Profiler rows are scan lines, columns pulses (a full
/// turn starting straight down). Labels are object ids; times are seconds since the epoch's start.
/// The epoch's registration error is applied to points and sensor positions. Deterministic
/// whatever the thread count. Throws ConfigError on out-of-range parameters.
/// Profiler mode gives one grid (lines x pulses); spinning mode one grid per turn (rings x
/// columns, columns wrapping), the sensor moving during the turn.
std::vector<SensorGrid> scan_epoch(const Scene& scene, std::size_t epoch, const ScannerParams& params);

/// Rays cast by scan_epoch for these parameters (for throughput figures).
std::uint64_t rays_per_epoch(const Scene& scene, std::size_t epoch, const ScannerParams& params);

/// Ground-truth label of a face that lies on no scene surface (it bridges a depth jump).
inline constexpr std::uint32_t kNoSurface = 0xFFFFFFFFu;

/// Per triangle of `mesh`: the id of the object whose surface (as present at the epoch) lies
/// nearest the triangle's centroid along the triangle's normal, within `tolerance` metres;
/// kNoSurface when none does. Labels faces by where they are rather than by their corners, so
/// that a sidewalk triangle with one corner on a wall counts as sidewalk.
std::vector<std::uint32_t> surface_labels(const Scene& scene, std::size_t epoch, const Mesh& mesh, float tolerance);

}  // namespace citymesh
