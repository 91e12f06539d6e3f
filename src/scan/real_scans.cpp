// SPDX-License-Identifier: MIT
// Building sensor grids from real scan-ordered files.
#include "citymesh/scan/real_scans.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

struct Pulse {
  Vec3d point, sensor;
  double time = 0, angle = 0;
  std::size_t line = 0;
};

/// Calls visit(pulse) for every chosen echo of every file, in order, with its scan line.
template <class Visit>
void for_each_pulse(const std::vector<std::filesystem::path>& files, const ProfilerGridParams& p, PlyReadParams read,
                    Visit&& visit) {
  read.extra_vertex_properties = {p.angle_property, p.echo_index_property, p.echo_count_property};
  read.require_sensor_origin = true;
  std::size_t line = 0;
  double previous = 0;
  bool first = true;
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
        if (!first && angle < previous - M_PI) ++line;  // the angle wrapped: next line
        first = false;
        previous = angle;
        visit(Pulse{v.positions[i], v.sensor_positions[i], v.times.empty() ? 0.0 : v.times[i], angle, line});
      }
    }
  }
}

/// What the first pass over the pulses finds: how many, the scan lines, the first point (the
/// grid's origin) and the median angle step between successive pulses of a line (ignoring
/// gaps and wraps).
struct PulseSurvey {
  std::size_t pulses = 0, lines = 0;
  Vec3d first_point;
  double step = 0;
};

PulseSurvey survey_pulses(const std::vector<std::filesystem::path>& files, const ProfilerGridParams& p,
                          const PlyReadParams& read) {
  PulseSurvey survey;
  std::vector<double> steps;
  Pulse previous;
  for_each_pulse(files, p, read, [&](const Pulse& pulse) {
    if (survey.pulses == 0) survey.first_point = pulse.point;
    const double d = pulse.angle - previous.angle;
    if (survey.pulses > 0 && pulse.line == previous.line && d > 0) steps.push_back(d);
    previous = pulse;
    ++survey.pulses;
    survey.lines = pulse.line + 1;
  });
  if (survey.pulses < 2) throw InputError(fmt::format("{}: too few points to mesh", files.front().string()));
  if (steps.empty()) throw InputError("mesh: too few pulses to find the angular step of the scanner");
  std::nth_element(steps.begin(), steps.begin() + std::ptrdiff_t(steps.size() / 2), steps.end());
  survey.step = steps[steps.size() / 2];
  return survey;
}

/// Puts a pulse in row `row` of `g` (whose columns are angle bins of `step`), unless its bin
/// holds one already (two pulses in one bin: the first is kept).
void place(SensorGrid& g, std::size_t row, const Pulse& p, double step) {
  const double turn = std::fmod(p.angle + 4 * M_PI, 2 * M_PI);
  const std::size_t cell = g.index(row, static_cast<std::size_t>(turn / step) % g.cols);
  if (g.valid[cell]) return;
  g.points[cell] = to_local(p.point, g.origin);
  g.sensors[cell] = to_local(p.sensor, g.origin);
  g.times[cell] = p.time;
  g.valid[cell] = 1;
}

std::size_t columns_of(double step) { return static_cast<std::size_t>(std::lround(2 * M_PI / step)); }

/// Makes `band` rows [first, first + height) of a grid of `lines` rows (height at most
/// `rows`), empty; with `keep_last`, its row 0 is the old band's last row (the next band
/// overlaps the one before by a row).
void start_band(SensorGrid& band, std::size_t first, std::size_t rows, std::size_t lines, bool keep_last) {
  const std::size_t cols = band.cols, height = std::min(rows, lines - first);
  if (!keep_last) {
    band.resize(height, cols, false);
    return;
  }
  const auto last = static_cast<std::ptrdiff_t>(band.index(band.rows - 1, 0)), n = static_cast<std::ptrdiff_t>(cols);
  const auto keep_last_row_only = [&](auto& cells) {
    if (last > 0) std::copy(cells.begin() + last, cells.begin() + last + n, cells.begin());  // rows never overlap
    cells.resize(height * cols);
    std::fill(cells.begin() + n, cells.end(), typename std::decay_t<decltype(cells)>::value_type{});
  };
  keep_last_row_only(band.points);
  keep_last_row_only(band.sensors);
  keep_last_row_only(band.times);
  keep_last_row_only(band.valid);
  band.rows = height;
}

}  // namespace

ProfilerGridShape for_each_profiler_band(const std::vector<std::filesystem::path>& files,
                                         const ProfilerGridParams& params, const ProfilerBandSize& size,
                                         const std::function<void(const SensorGrid&)>& visit, PlyReadParams read) {
  const PulseSurvey survey = survey_pulses(files, params, read);
  const ProfilerGridShape shape{survey.lines, columns_of(survey.step), whole_metre_origin(survey.first_point)};
  const std::size_t rows = std::max<std::size_t>(2, size.rows > 0 ? size.rows : size.cells / shape.cols);
  SensorGrid band;
  band.cols = shape.cols;
  band.wrap_columns = true;
  band.origin = shape.origin;
  std::size_t first = 0;  // the band's row 0 in the whole grid
  start_band(band, first, rows, shape.rows, false);
  for_each_pulse(files, params, std::move(read), [&](const Pulse& p) {
    while (p.line >= first + band.rows) {  // the band is full: mesh it, go on from its last row
      visit(band);
      first += band.rows - 1;
      start_band(band, first, rows, shape.rows, true);
    }
    place(band, p.line - first, p, survey.step);
  });
  visit(band);
  return shape;
}

SensorGrid profiler_grid(const std::vector<std::filesystem::path>& files, const ProfilerGridParams& params,
                         PlyReadParams read) {
  // Two passes over the files, so that the pulses are never all held (72 bytes each, and the
  // list's regrowth, were the peak of meshing a long drive): the first finds the lines and
  // the angular step, the second fills the grid.
  const PulseSurvey survey = survey_pulses(files, params, read);
  SensorGrid g;
  g.resize(survey.lines, columns_of(survey.step), false);
  g.wrap_columns = true;
  g.origin = whole_metre_origin(survey.first_point);
  for_each_pulse(files, params, std::move(read), [&](const Pulse& p) { place(g, p.line, p, survey.step); });
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
