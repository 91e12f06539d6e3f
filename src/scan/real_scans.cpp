// SPDX-License-Identifier: MIT
// Building sensor grids from real scan-ordered files.
#include "citymesh/scan/real_scans.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

struct Pulse {
  Vec3d point, sensor;
  double time = 0, angle = 0;
  std::size_t line = 0;
};

/// Reads every chosen echo of every file, in order, and numbers the scan lines.
std::vector<Pulse> read_pulses(const std::vector<std::filesystem::path>& files, const ProfilerGridParams& p,
                               PlyReadParams read) {
  read.extra_vertex_properties = {p.angle_property, p.echo_index_property, p.echo_count_property};
  read.require_sensor_origin = true;
  std::vector<Pulse> pulses;
  std::size_t line = 0;
  double previous = 0;
  for (const auto& file : files) {
    PlyReader reader(file, read);
    PlyVertexChunk v;
    PlyFaceChunk f;
    for (auto kind = reader.next(v, f); kind != PlyReader::ChunkKind::end; kind = reader.next(v, f)) {
      if (kind != PlyReader::ChunkKind::vertices) continue;
      for (std::size_t i = 0; i < v.positions.size(); ++i) {
        const double angle = v.extras[0][i], echo = v.extras[1][i], echoes = v.extras[2][i];
        const bool chosen = p.echo == ProfilerGridParams::Echo::first ? echo == 1 : echo == echoes;
        if (!chosen) continue;
        if (!pulses.empty() && angle < previous - M_PI) ++line;  // the angle wrapped: next line
        previous = angle;
        pulses.push_back({v.positions[i], v.sensor_positions[i], v.times.empty() ? 0.0 : v.times[i], angle, line});
      }
    }
  }
  return pulses;
}

/// Median angle step between successive pulses of a line (ignoring gaps and wraps).
double median_step(const std::vector<Pulse>& pulses) {
  std::vector<double> steps;
  for (std::size_t i = 1; i < pulses.size(); ++i) {
    const double d = pulses[i].angle - pulses[i - 1].angle;
    if (pulses[i].line == pulses[i - 1].line && d > 0) steps.push_back(d);
  }
  if (steps.empty()) throw InputError("mesh: too few pulses to find the angular step of the scanner");
  std::nth_element(steps.begin(), steps.begin() + std::ptrdiff_t(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}

}  // namespace

SensorGrid profiler_grid(const std::vector<std::filesystem::path>& files, const ProfilerGridParams& params,
                         PlyReadParams read) {
  const std::vector<Pulse> pulses = read_pulses(files, params, std::move(read));
  if (pulses.size() < 2) throw InputError(fmt::format("{}: too few points to mesh", files.front().string()));
  const double step = median_step(pulses);
  const auto cols = static_cast<std::size_t>(std::lround(2 * M_PI / step));
  SensorGrid g;
  g.resize(pulses.back().line + 1, cols, false);
  g.wrap_columns = true;
  g.origin = whole_metre_origin(pulses.front().point);
  for (const Pulse& p : pulses) {
    const double turn = std::fmod(p.angle + 4 * M_PI, 2 * M_PI);
    const std::size_t cell = g.index(p.line, static_cast<std::size_t>(turn / step) % cols);
    if (g.valid[cell]) continue;  // two pulses in one bin: keep the first
    g.points[cell] = to_local(p.point, g.origin);
    g.sensors[cell] = to_local(p.sensor, g.origin);
    g.times[cell] = p.time;
    g.valid[cell] = 1;
  }
  return g;
}

SensorGrid spinning_grid(const std::filesystem::path& file, PlyReadParams read) {
  read.extra_vertex_properties = {"ring", "column", "valid"};
  read.require_sensor_origin = true;
  PlyReader reader(file, read);
  struct Return {
    Vec3d point, sensor;
    double time;
    std::size_t ring, column;
  };
  std::vector<Return> returns;
  std::size_t rings = 0, columns = 0;
  PlyVertexChunk v;
  PlyFaceChunk f;
  for (auto kind = reader.next(v, f); kind != PlyReader::ChunkKind::end; kind = reader.next(v, f)) {
    if (kind != PlyReader::ChunkKind::vertices) continue;
    for (std::size_t i = 0; i < v.positions.size(); ++i) {
      const double ring = v.extras[0][i], column = v.extras[1][i];
      if (ring < 0 || column < 0 || ring > 4096 || column > 65536) {
        throw InputError(fmt::format("{}: vertex {}: ring {} or column {} out of range", file.string(), v.first + i, ring, column));
      }
      rings = std::max(rings, std::size_t(ring) + 1);
      columns = std::max(columns, std::size_t(column) + 1);
      if (v.extras[2][i] == 0 || v.positions[i] == v.sensor_positions[i]) continue;  // no return
      returns.push_back({v.positions[i], v.sensor_positions[i], v.times.empty() ? 0.0 : v.times[i],
                         std::size_t(ring), std::size_t(column)});
    }
  }
  if (returns.empty()) throw InputError(fmt::format("{}: no valid return to mesh", file.string()));
  SensorGrid g;
  g.resize(rings, columns, false);
  g.wrap_columns = true;
  g.origin = whole_metre_origin(returns.front().point);
  for (const Return& r : returns) {
    const std::size_t cell = g.index(r.ring, r.column);
    g.points[cell] = to_local(r.point, g.origin);
    g.sensors[cell] = to_local(r.sensor, g.origin);
    g.times[cell] = r.time;
    g.valid[cell] = 1;
  }
  return g;
}

}  // namespace citymesh
