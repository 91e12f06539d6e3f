// SPDX-License-Identifier: MIT
// Meshing the real samples of ../shared/data/real (skipped when absent).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>

#include <cstring>
#include <unordered_map>

#include "citymesh/scan/real_scans.h"
#include "test_support.h"

namespace citymesh {
namespace {

std::uint64_t key(const Vec3f& p) {
  std::uint32_t x, y;
  std::memcpy(&x, &p.x, 4);
  std::memcpy(&y, &p.y, 4);
  return (std::uint64_t(x) << 32) ^ y ^ (std::uint64_t(std::hash<float>{}(p.z)) << 16);
}

/// Checks every triangle against the grid it came from: its vertices are neighbouring cells
/// (adjacent lines and columns), its edges are within the range-dependent limit, and it does
/// not span a depth jump. Returns the number of triangles checked.
std::size_t check_topology(const SensorGrid& g, const SensorMeshResult& r, const SensorMeshingParams& p) {
  std::unordered_map<std::uint64_t, std::size_t> cell_of;
  for (std::size_t i = 0; i < g.points.size(); ++i) {
    if (g.valid[i]) cell_of[key(g.points[i])] = i;
  }
  for (const Triangle& t : r.mesh.triangles) {
    std::size_t cells[3];
    float range[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3f& v = r.mesh.positions[t[k]];
      cells[k] = cell_of.at(key(v));
      range[k] = norm(v - r.mesh.sensor_positions[t[k]]);
    }
    for (int k = 0; k < 3; ++k) {
      const std::size_t a = cells[k], b = cells[(k + 1) % 3];
      const std::size_t ra = a / g.cols, rb = b / g.cols, ca = a % g.cols, cb = b % g.cols;
      const std::size_t dc = std::min((ca + g.cols - cb) % g.cols, (cb + g.cols - ca) % g.cols);
      EXPECT_LE(std::max(ra, rb) - std::min(ra, rb), 1u);
      EXPECT_LE(dc, 1u);
      const float len = norm(r.mesh.positions[t[k]] - r.mesh.positions[t[(k + 1) % 3]]);
      EXPECT_LE(len, p.max_edge_base + p.max_edge_per_metre * std::max(range[k], range[(k + 1) % 3]) + 1e-4f);
    }
    const float lo = std::min({range[0], range[1], range[2]}), hi = std::max({range[0], range[1], range[2]});
    EXPECT_LE(hi - lo, p.max_depth_jump * lo + 1e-4f);
  }
  return r.mesh.triangle_count();
}

TEST(RealScans, StereopolisProfilerLinesMeshNeighbouringPulsesOnly) {
  const auto dir = test::real_data_dir();
  if (dir.empty()) GTEST_SKIP() << "real data absent";
  std::vector<std::filesystem::path> files;
  for (int k = 1; k <= 5; ++k) files.push_back(dir / fmt::format("terramobilita_riegl_paris2013/sample_riegl_18_0{}.ply", k));
  const SensorGrid g = profiler_grid(files, {});
  // ~14 angle wraps per file, 0.12° pulses: 67-68 lines of ~2900 bins
  EXPECT_GE(g.rows, 66u);
  EXPECT_LE(g.rows, 70u);
  EXPECT_NEAR(double(g.cols), 2900.0, 30.0);
  const auto points = static_cast<std::size_t>(std::count(g.valid.begin(), g.valid.end(), 1));
  EXPECT_GT(points, 130000u);  // first echoes of 150 000 returns
  const SensorMeshingParams p;
  const SensorMeshResult r = mesh_sensor_grid(g, p);
  // A full grid gives 2 triangles per point; holes, sky and rejected edges take some away.
  EXPECT_GE(r.mesh.triangle_count(), points * 6 / 5);
  EXPECT_LE(r.mesh.triangle_count(), points * 2);
  check_topology(g, r, p);
}

TEST(RealScans, OusterFrameMeshesItsRingGrid) {
  const auto dir = test::real_data_dir();
  if (dir.empty()) GTEST_SKIP() << "real data absent";
  const SensorGrid g = spinning_grid(dir / "ouster_os1_128_walk3/ouster_os1_128_frame1795.ply");
  EXPECT_EQ(g.rows, 128u);
  EXPECT_EQ(g.cols, 1024u);
  const auto points = static_cast<std::size_t>(std::count(g.valid.begin(), g.valid.end(), 1));
  EXPECT_GT(points, 90000u);
  const SensorMeshingParams p;
  const SensorMeshResult r = mesh_sensor_grid(g, p);
  EXPECT_GE(r.mesh.triangle_count(), points / 2);
  EXPECT_LE(r.mesh.triangle_count(), points * 2);
  check_topology(g, r, p);
}

}  // namespace
}  // namespace citymesh
