// SPDX-License-Identifier: MIT
// Points in the order the sensor measured them, and their meshing by sensor topology.
#pragma once

#include <cstdint>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh {

/// rows x cols measurements: rows are scan lines (profiler) or rings (spinning sensor),
/// columns are successive pulses along a line or azimuth steps. Cell (r, c) is at r * cols + c.
/// Cells without a return have valid = 0. Positions are floats relative to `origin`.
struct SensorGrid {
  std::size_t rows = 0, cols = 0;
  Vec3d origin;
  std::vector<Vec3f> points;
  std::vector<Vec3f> sensors;
  std::vector<double> times;
  std::vector<std::uint8_t> valid;
  std::vector<std::uint32_t> labels;  ///< optional per-cell label (simulation: object id)
  /// True when column cols-1 neighbours column 0 (a full 360° sweep of a spinning sensor).
  bool wrap_columns = false;

  void resize(std::size_t r, std::size_t c, bool with_labels);
  [[nodiscard]] std::size_t index(std::size_t r, std::size_t c) const { return r * cols + c; }
};

/// Which neighbour pairs may be joined into triangles.
struct SensorMeshingParams {
  /// An edge may be at most max_edge_base + max_edge_per_metre * range long (metres): the
  /// sampling spacing grows with range, so does the gap that still counts as one surface.
  float max_edge_base = 0.3f;
  float max_edge_per_metre = 0.08f;
  /// Largest relative range difference between two vertices of a triangle (|ra - rb| / min);
  /// larger means a depth jump between a foreground object and the background.
  float max_depth_jump = 0.25f;
  /// Largest angle between the triangle normal and its line of sight (degrees): beyond it the
  /// triangle is grazing and its geometry is unreliable.
  float max_incidence_deg = 86.0f;
};

struct SensorMeshStats {
  std::uint64_t candidates = 0;
  std::uint64_t rejected_long_edge = 0;
  std::uint64_t rejected_depth_jump = 0;
  std::uint64_t rejected_grazing = 0;
  /// Adds another grid's figures (a drive meshed band by band or frame by frame).
  SensorMeshStats& operator+=(const SensorMeshStats& o) {
    candidates += o.candidates;
    rejected_long_edge += o.rejected_long_edge;
    rejected_depth_jump += o.rejected_depth_jump;
    rejected_grazing += o.rejected_grazing;
    return *this;
  }
};

struct SensorMeshResult {
  Mesh mesh;  ///< vertices: the valid cells used by a triangle, in order of first use
  std::vector<std::uint32_t> face_labels;  ///< per triangle, when the grid has labels
  SensorMeshStats stats;
};

/// Meshes a sensor grid by its topology: each cell quad (r, c), (r, c+1), (r+1, c), (r+1, c+1)
/// gives up to two triangles (the shorter diagonal when all four are valid), each kept only if
/// every edge passes the range-dependent length test, its ranges show no depth jump, and it is
/// not grazing. Triangle ids are (acquisition, cell index of the quad, 0 or 1).
/// A face's label is the label shared by at least two of its vertices, else the label of its
/// nearest vertex. Deterministic.
SensorMeshResult mesh_sensor_grid(const SensorGrid& grid, const SensorMeshingParams& params = {},
                                  std::uint32_t acquisition = 0);

/// Where a band of consecutive rows sits in a grid meshed band by band (mesh_sensor_band),
/// and what the band before left for it. Starts as the first band's (row 0, vertex 0).
struct SensorBand {
  std::size_t first_row = 0;       ///< the band's row 0 is this row of the whole grid
  std::uint32_t first_vertex = 0;  ///< the id the band's first new vertex gets
  /// Per column of the band's row 0 (the previous band's last row): the vertex id that cell
  /// got there, or UINT32_MAX; empty for the first band.
  std::vector<std::uint32_t> carried;
};

/// Meshes a grid that is never whole in memory (a long profiler drive), a band of rows at a
/// time: `band` holds rows where.first_row ... of the whole grid, its row 0 repeating the
/// previous band's last row (for all bands but the first). Gives the triangles, ids and
/// orientations mesh_sensor_grid() gives the band's quads in the whole grid, with the vertices
/// numbered on from where.first_vertex in order of first use: the bands' results, appended,
/// are the whole grid's mesh. Returns the band's new vertices only (triangles name earlier
/// bands' vertices by their ids) and advances `where` to the next band.
SensorMeshResult mesh_sensor_band(const SensorGrid& band, const SensorMeshingParams& params, std::uint32_t acquisition,
                                  SensorBand& where);

}  // namespace citymesh
