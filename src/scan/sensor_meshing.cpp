// SPDX-License-Identifier: MIT
// Sensor-topology meshing (as in mobile-LiDAR "sensor meshing": triangles between successive
// pulses of a line and the same pulse of successive lines).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "citymesh/core/error.h"
#include "citymesh/scan/sensor_grid.h"

namespace citymesh {

void SensorGrid::resize(std::size_t r, std::size_t c, bool with_labels) {
  rows = r;
  cols = c;
  points.assign(r * c, {});
  sensors.assign(r * c, {});
  times.assign(r * c, 0.0);
  valid.assign(r * c, 0);
  labels.assign(with_labels ? r * c : 0, 0);
}

namespace {

class Mesher {
 public:
  Mesher(const SensorGrid& g, const SensorMeshingParams& p, std::uint32_t acquisition, SensorBand& where)
      : g_(g),
        p_(p),
        acquisition_(acquisition),
        cos_limit_(std::cos(p.max_incidence_deg * float(M_PI) / 180.0f)),
        where_(where) {}

  SensorMeshResult run() {
    check();
    vertex_of_.assign(g_.points.size(), kNone);
    std::copy(where_.carried.begin(), where_.carried.end(), vertex_of_.begin());
    // Every range is needed by up to six triangles' tests: compute each once.
    range_.resize(g_.points.size());
    std::size_t valid_cells = 0;
    for (std::size_t i = 0; i < range_.size(); ++i) {
      range_[i] = g_.valid[i] ? norm(g_.points[i] - g_.sensors[i]) : 0.0f;
      valid_cells += g_.valid[i] != 0 ? 1 : 0;
    }
    result_.mesh.origin = g_.origin;
    if (g_.rows == 0) return std::move(result_);
    reserve_for(valid_cells);
    const std::size_t col_end = g_.wrap_columns ? g_.cols : g_.cols - 1;
    for (std::size_t r = 0; r + 1 < g_.rows; ++r) {
      for (std::size_t c = 0; c < col_end; ++c) quad(r, c, (c + 1) % g_.cols);
    }
    // What the next band, whose row 0 is this band's last row, starts from.
    const auto last_row = vertex_of_.begin() + static_cast<std::ptrdiff_t>(g_.index(g_.rows - 1, 0));
    where_.carried.assign(last_row, last_row + static_cast<std::ptrdiff_t>(g_.cols));
    where_.first_row += g_.rows - 1;
    where_.first_vertex = next_vertex();
    return std::move(result_);
  }

 private:
  static constexpr std::uint32_t kNone = UINT32_MAX;

  /// Room for what a grid of `cells` valid cells gives: a vertex per cell at most, and two
  /// triangles per cell (a full grid's count; a ragged one may need more, and grows as
  /// before). Grown by doubling from nothing, the arrays peaked at up to three times their
  /// final size while a long drive's mesh was made (the peak of `citymesh mesh`).
  void reserve_for(std::size_t cells) {
    Mesh& m = result_.mesh;
    m.positions.reserve(cells);
    m.sensor_positions.reserve(cells);
    m.times.reserve(cells);
    m.triangles.reserve(2 * cells);
    m.triangle_ids.reserve(2 * cells);
    if (!g_.labels.empty()) result_.face_labels.reserve(2 * cells);
  }

  void check() const {
    const std::size_t n = g_.rows * g_.cols;
    if (!where_.carried.empty() && (where_.carried.size() != g_.cols || g_.rows == 0)) {
      throw ProcessingError(
          fmt::format("sensor meshing: a band of {} columns follows one of {}", g_.cols, where_.carried.size()));
    }
    if (g_.points.size() != n || g_.sensors.size() != n || g_.valid.size() != n || g_.times.size() != n ||
        (!g_.labels.empty() && g_.labels.size() != n) || g_.cols < 2) {
      throw ProcessingError(fmt::format("sensor meshing: grid of {} x {} has inconsistent arrays", g_.rows, g_.cols));
    }
  }

  /// The length / depth-jump / grazing tests; counts the reason of a rejection. On success
  /// `normal` holds the (unnormalised) normal of a-b-c, reused to orient the triangle.
  bool acceptable(std::size_t a, std::size_t b, std::size_t c, Vec3f& normal) {
    ++result_.stats.candidates;
    const float ra = range_[a], rb = range_[b], rc = range_[c];
    const std::size_t v[3] = {a, b, c};
    const float r[3] = {ra, rb, rc};
    for (int e = 0; e < 3; ++e) {
      const std::size_t i = v[e], j = v[(e + 1) % 3];
      const float limit = p_.max_edge_base + p_.max_edge_per_metre * std::max(r[e], r[(e + 1) % 3]);
      if (norm(g_.points[i] - g_.points[j]) > limit) return reject(result_.stats.rejected_long_edge);
    }
    const float rmin = std::min({ra, rb, rc}), rmax = std::max({ra, rb, rc});
    if (rmax - rmin > p_.max_depth_jump * rmin) return reject(result_.stats.rejected_depth_jump);
    normal = cross(g_.points[b] - g_.points[a], g_.points[c] - g_.points[a]);
    const Vec3f view = (g_.sensors[a] + g_.sensors[b] + g_.sensors[c]) / 3.0f -
                       (g_.points[a] + g_.points[b] + g_.points[c]) / 3.0f;
    const float nn = norm(normal), vn = norm(view);
    if (nn == 0.0f || vn == 0.0f || std::abs(dot(normal, view)) < cos_limit_ * nn * vn) {
      return reject(result_.stats.rejected_grazing);
    }
    return true;
  }
  static bool reject(std::uint64_t& counter) {
    ++counter;
    return false;
  }

  /// The id the next new vertex gets (the ids go on from the bands before).
  std::uint32_t next_vertex() const {
    const std::uint64_t id = std::uint64_t{where_.first_vertex} + result_.mesh.positions.size();
    if (id >= kNone) throw ProcessingError("sensor meshing: more than 2^32 - 1 vertices in one mesh");
    return static_cast<std::uint32_t>(id);
  }

  std::uint32_t vertex(std::size_t cell) {
    if (vertex_of_[cell] == kNone) {
      Mesh& m = result_.mesh;
      vertex_of_[cell] = next_vertex();
      m.positions.push_back(g_.points[cell]);
      m.sensor_positions.push_back(g_.sensors[cell]);
      m.times.push_back(g_.times[cell]);
    }
    return vertex_of_[cell];
  }

  std::uint32_t face_label(std::size_t a, std::size_t b, std::size_t c) const {
    const auto& l = g_.labels;
    if (l[a] == l[b] || l[a] == l[c]) return l[a];
    if (l[b] == l[c]) return l[b];
    const float ra = range_[a], rb = range_[b], rc = range_[c];
    return ra <= rb && ra <= rc ? l[a] : (rb <= rc ? l[b] : l[c]);
  }

  /// Emits triangle a-b-c oriented to face its sensor.
  void emit(std::size_t a, std::size_t b, std::size_t c, std::size_t quad_cell, std::uint32_t which) {
    Vec3f n;
    if (!acceptable(a, b, c, n)) return;
    if (dot(n, g_.sensors[a] - g_.points[a]) < 0) std::swap(b, c);
    Mesh& m = result_.mesh;
    m.triangles.push_back({vertex(a), vertex(b), vertex(c)});
    m.triangle_ids.push_back({acquisition_, which, where_.first_row * g_.cols + quad_cell});
    if (!g_.labels.empty()) result_.face_labels.push_back(face_label(a, b, c));
  }

  void quad(std::size_t r, std::size_t c0, std::size_t c1) {
    const std::size_t a = g_.index(r, c0), b = g_.index(r, c1), c = g_.index(r + 1, c0), d = g_.index(r + 1, c1);
    const bool va = g_.valid[a], vb = g_.valid[b], vc = g_.valid[c], vd = g_.valid[d];
    const int count = va + vb + vc + vd;
    if (count < 3) return;
    if (count == 3) {
      if (!va) emit(b, d, c, a, 0);
      else if (!vb) emit(a, d, c, a, 0);
      else if (!vc) emit(a, b, d, a, 0);
      else emit(a, b, c, a, 0);
      return;
    }
    // Split along the shorter diagonal: it follows the surface better.
    if (norm(g_.points[a] - g_.points[d]) <= norm(g_.points[b] - g_.points[c])) {
      emit(a, b, d, a, 0);
      emit(a, d, c, a, 1);
    } else {
      emit(a, b, c, a, 0);
      emit(b, d, c, a, 1);
    }
  }

  const SensorGrid& g_;
  const SensorMeshingParams& p_;
  std::uint32_t acquisition_;
  float cos_limit_;
  std::vector<std::uint32_t> vertex_of_;
  std::vector<float> range_;  ///< sensor-to-point distance per cell
  SensorBand& where_;
  SensorMeshResult result_;
};

}  // namespace

SensorMeshResult mesh_sensor_grid(const SensorGrid& grid, const SensorMeshingParams& params,
                                  std::uint32_t acquisition) {
  SensorBand whole;
  return Mesher(grid, params, acquisition, whole).run();
}

SensorMeshResult mesh_sensor_band(const SensorGrid& band, const SensorMeshingParams& params, std::uint32_t acquisition,
                                  SensorBand& where) {
  return Mesher(band, params, acquisition, where).run();
}

}  // namespace citymesh
