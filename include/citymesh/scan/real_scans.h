// SPDX-License-Identifier: MIT
// Sensor grids from real scan-ordered point files (PLY with per-point sensor origin).
#pragma once

#include <filesystem>
#include <functional>
#include <vector>

#include "citymesh/io/ply_reader.h"
#include "citymesh/scan/sensor_grid.h"

namespace citymesh {

struct ProfilerGridParams {
  /// Which return of a multi-echo pulse becomes the grid point. The first echo is the default:
  /// the space in front of the first return is known to be empty, while a later echo (behind
  /// foliage, say) would claim the partly-hit space before it as empty too.
  enum class Echo { first, last };
  Echo echo = Echo::first;
  std::string angle_property = "theta";          ///< scan angle, radians
  std::string echo_index_property = "num_echo";  ///< 1-based index of this echo
  std::string echo_count_property = "nb_of_echo";
};

/// A rotating 2D profiler (e.g. the Stereopolis II Riegl): points in acquisition order across
/// `files` (consecutive chunks of one drive). A scan line ends where the angle wraps around;
/// columns are angle bins of the median pulse step, so the same angle in successive lines
/// shares a column. Throws InputError naming the file when a property is missing.
SensorGrid profiler_grid(const std::vector<std::filesystem::path>& files, const ProfilerGridParams& params,
                         PlyReadParams read = {});

struct ProfilerGridShape {
  std::size_t rows = 0, cols = 0;  ///< of the whole grid profiler_grid() would make
  Vec3d origin;
};

/// How many rows a band of a profiler grid holds: `rows` when not 0, else as many as make
/// about `cells` cells; at least 2 (a quad's two rows).
struct ProfilerBandSize {
  std::size_t rows = 0;
  std::size_t cells = std::size_t{1} << 20;
};

/// profiler_grid()'s grid a band of rows at a time, so that a long drive's grid is never whole
/// in memory: visit(band) for each band of consecutive rows, in order, whose row 0 repeats the
/// band before's last row (the input of mesh_sensor_band). The bands hold exactly the whole
/// grid's cells. Reads the files twice.
ProfilerGridShape for_each_profiler_band(const std::vector<std::filesystem::path>& files,
                                         const ProfilerGridParams& params, const ProfilerBandSize& size,
                                         const std::function<void(const SensorGrid&)>& visit, PlyReadParams read = {});

/// A spinning multi-beam sensor frame (e.g. an Ouster OS-1): integer `ring` and `column`
/// properties place each point, `valid` = 0 marks missing returns. Columns wrap around.
SensorGrid spinning_grid(const std::filesystem::path& file, PlyReadParams read = {});

}  // namespace citymesh
