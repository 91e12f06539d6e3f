// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "citymesh/scan/sensor_grid.h"

namespace citymesh {
namespace {

/// rows x cols points on the plane z = 0 with the given spacing, seen from 5 m above.
SensorGrid plane(std::size_t rows, std::size_t cols, float spacing, float height = 5.0f) {
  SensorGrid g;
  g.resize(rows, cols, true);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      const std::size_t i = g.index(r, c);
      g.points[i] = {float(r) * spacing, float(c) * spacing, 0.0f};
      g.sensors[i] = {float(r) * spacing, 0.0f, height};
      g.valid[i] = 1;
      g.labels[i] = 7;
    }
  }
  return g;
}

float range(const SensorGrid& /*grid*/, const Mesh& m, std::uint32_t v) { return norm(m.positions[v] - m.sensor_positions[v]); }

TEST(SensorMeshing, FullGridGivesTwoTrianglesPerCellFacingTheSensor) {
  const SensorGrid g = plane(10, 10, 0.1f);
  const SensorMeshResult r = mesh_sensor_grid(g);
  EXPECT_EQ(r.mesh.triangle_count(), 2u * 9 * 9);
  EXPECT_EQ(r.mesh.vertex_count(), 100u);
  EXPECT_NO_THROW(r.mesh.check_invariants());
  for (const Triangle& t : r.mesh.triangles) {
    const Vec3f n = cross(r.mesh.positions[t[1]] - r.mesh.positions[t[0]], r.mesh.positions[t[2]] - r.mesh.positions[t[0]]);
    EXPECT_GT(dot(n, r.mesh.sensor_positions[t[0]] - r.mesh.positions[t[0]]), 0.0f);
  }
  EXPECT_EQ(r.face_labels, std::vector<std::uint32_t>(r.mesh.triangle_count(), 7));
}

TEST(SensorMeshing, MissingReturnLeavesOneTriangleInEachTouchingCell) {
  SensorGrid g = plane(10, 10, 0.1f);
  g.valid[g.index(4, 4)] = 0;
  EXPECT_EQ(mesh_sensor_grid(g).mesh.triangle_count(), 2u * 81 - 4);
}

TEST(SensorMeshing, NoTriangleAcrossADepthJump) {
  SensorGrid g = plane(12, 12, 0.1f);
  for (std::size_t r = 0; r < 12; ++r) {
    for (std::size_t c = 6; c < 12; ++c) g.points[g.index(r, c)].z = -3.0f;  // a 3 m step down
  }
  const SensorMeshResult res = mesh_sensor_grid(g);
  EXPECT_GT(res.stats.rejected_depth_jump + res.stats.rejected_long_edge, 0u);
  for (const Triangle& t : res.mesh.triangles) {
    const float a = range(g, res.mesh, t[0]), b = range(g, res.mesh, t[1]), c = range(g, res.mesh, t[2]);
    EXPECT_LE(std::max({a, b, c}) - std::min({a, b, c}), 0.25f * std::min({a, b, c}));
  }
  EXPECT_EQ(res.mesh.triangle_count(), 2u * 11 * 5 * 2);  // both flat halves, nothing between
}

TEST(SensorMeshing, EdgesLongerThanTheRangeDependentLimitAreRefused) {
  // At ~5 m range the limit is about 0.3 + 0.08 * 5.1 = 0.71 m. With 0.45 m spacing the quad
  // diagonal is 0.64 m and meshes; with 0.8 m spacing even the sides are too long.
  EXPECT_EQ(mesh_sensor_grid(plane(4, 4, 0.45f)).mesh.triangle_count(), 18u);
  const SensorMeshResult far = mesh_sensor_grid(plane(4, 4, 0.8f));
  EXPECT_EQ(far.mesh.triangle_count(), 0u);
  EXPECT_EQ(far.stats.rejected_long_edge, far.stats.candidates);
}

TEST(SensorMeshing, GrazingTrianglesAreRefused) {
  // The plane z = 0 seen from a sensor 1 cm above it, 20 m away: the line of sight is almost
  // parallel to the surface.
  SensorGrid g = plane(6, 6, 0.1f);
  for (std::size_t i = 0; i < g.points.size(); ++i) g.sensors[i] = g.points[i] + Vec3f{0, -20.0f, 0.01f};
  SensorMeshingParams p;
  p.max_edge_per_metre = 1.0f;  // let only the incidence test decide
  p.max_depth_jump = 10.0f;
  const SensorMeshResult r = mesh_sensor_grid(g, p);
  EXPECT_EQ(r.mesh.triangle_count(), 0u);
  EXPECT_EQ(r.stats.rejected_grazing, r.stats.candidates);
}

TEST(SensorMeshing, WrappedColumnsCloseTheRing) {
  // A cylinder of radius 5 around a sensor on its axis: 8 rings x 64 columns.
  SensorGrid g;
  g.resize(8, 64, false);
  g.wrap_columns = true;
  for (std::size_t r = 0; r < 8; ++r) {
    for (std::size_t c = 0; c < 64; ++c) {
      const float a = float(c) * 2.0f * float(M_PI) / 64.0f;
      g.points[g.index(r, c)] = {5 * std::cos(a), 5 * std::sin(a), float(r) * 0.3f};
      g.sensors[g.index(r, c)] = {0, 0, float(r) * 0.3f};
      g.valid[g.index(r, c)] = 1;
    }
  }
  EXPECT_EQ(mesh_sensor_grid(g).mesh.triangle_count(), 2u * 7 * 64);
  g.wrap_columns = false;
  EXPECT_EQ(mesh_sensor_grid(g).mesh.triangle_count(), 2u * 7 * 63);
}

TEST(SensorMeshing, LabelIsTheMajorityOfTheVertices) {
  SensorGrid g = plane(6, 6, 0.1f);
  for (std::size_t i = 0; i < g.labels.size(); ++i) g.labels[i] = static_cast<std::uint32_t>(i % 3);
  const SensorMeshResult r = mesh_sensor_grid(g);
  ASSERT_EQ(r.face_labels.size(), r.mesh.triangle_count());
  for (std::size_t f = 0; f < r.mesh.triangle_count(); ++f) {
    std::uint32_t l[3];
    for (int k = 0; k < 3; ++k) {  // back from the vertex position to its grid cell
      const Vec3f p = r.mesh.positions[r.mesh.triangles[f][k]];
      l[k] = g.labels[g.index(std::size_t(std::lround(p.x / 0.1f)), std::size_t(std::lround(p.y / 0.1f)))];
    }
    if (l[0] == l[1] || l[0] == l[2]) {
      EXPECT_EQ(r.face_labels[f], l[0]);
    } else if (l[1] == l[2]) {
      EXPECT_EQ(r.face_labels[f], l[1]);
    } else {  // all differ: one of them (the nearest vertex's)
      EXPECT_TRUE(r.face_labels[f] == l[0] || r.face_labels[f] == l[1] || r.face_labels[f] == l[2]);
    }
  }
}

TEST(SensorMeshing, RandomGridsOnlyJoinGridNeighboursWithinLimits) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> jitter(-0.5f, 0.5f);
  std::bernoulli_distribution hole(0.1);
  SensorGrid g = plane(30, 30, 0.2f);
  for (std::size_t i = 0; i < g.points.size(); ++i) {
    g.points[i].z += jitter(rng);
    g.valid[i] = !hole(rng);
  }
  const SensorMeshingParams p;
  const SensorMeshResult r = mesh_sensor_grid(g, p);
  EXPECT_GT(r.mesh.triangle_count(), 500u);
  for (std::size_t f = 0; f < r.mesh.triangle_count(); ++f) {
    const Triangle& t = r.mesh.triangles[f];
    for (int e = 0; e < 3; ++e) {
      const float ra = range(g, r.mesh, t[e]), rb = range(g, r.mesh, t[(e + 1) % 3]);
      const float len = norm(r.mesh.positions[t[e]] - r.mesh.positions[t[(e + 1) % 3]]);
      EXPECT_LE(len, p.max_edge_base + p.max_edge_per_metre * std::max(ra, rb) + 1e-5f);
    }
    // Grid neighbours: the quad cell recorded in the id spans rows r..r+1 and cols c..c+1.
    const std::size_t cell = r.mesh.triangle_ids[f].face;
    for (std::uint32_t v : t) {
      const Vec3f p0 = g.points[cell];
      EXPECT_LE(std::abs(r.mesh.positions[v].x - p0.x), 0.2f + 1e-4f);
      EXPECT_LE(std::abs(r.mesh.positions[v].y - p0.y), 0.2f + 1e-4f);
    }
  }
}

/// Rows [first, first + height) of `g`.
SensorGrid rows_of(const SensorGrid& g, std::size_t first, std::size_t height) {
  SensorGrid band;
  band.resize(height, g.cols, !g.labels.empty());
  band.origin = g.origin;
  band.wrap_columns = g.wrap_columns;
  const auto from = static_cast<std::ptrdiff_t>(g.index(first, 0)), n = static_cast<std::ptrdiff_t>(height * g.cols);
  std::copy(g.points.begin() + from, g.points.begin() + from + n, band.points.begin());
  std::copy(g.sensors.begin() + from, g.sensors.begin() + from + n, band.sensors.begin());
  std::copy(g.times.begin() + from, g.times.begin() + from + n, band.times.begin());
  std::copy(g.valid.begin() + from, g.valid.begin() + from + n, band.valid.begin());
  if (!g.labels.empty()) std::copy(g.labels.begin() + from, g.labels.begin() + from + n, band.labels.begin());
  return band;
}

TEST(SensorMeshing, BandsMeshedOneAfterAnotherGiveTheWholeGridsMesh) {
  // A bumpy, holed grid (some quads lose a corner, some triangles are refused), meshed whole
  // and in bands of each height, each band repeating the last row of the one before.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> bump(-0.05f, 0.05f);
  for (const bool wrap : {false, true}) {
    SensorGrid g = plane(23, 17, 0.1f);
    g.wrap_columns = wrap;
    for (std::size_t i = 0; i < g.points.size(); ++i) {
      g.points[i].z += bump(rng) + (rng() % 15 == 0 ? 1.0f : 0.0f);  // a spike: its edges are too long
      g.times[i] = 0.001 * static_cast<double>(i);
      g.labels[i] = static_cast<std::uint32_t>(rng() % 3);
      g.valid[i] = rng() % 9 != 0 ? 1 : 0;
    }
    const SensorMeshResult whole = mesh_sensor_grid(g, {}, 4);
    ASSERT_GT(whole.stats.rejected_long_edge, 0u);
    for (const std::size_t height : {2, 3, 5, 22, 23}) {
      SensorBand where;
      SensorMeshResult joined;
      for (std::size_t first = 0; first + 1 < g.rows; first += height - 1) {
        ASSERT_EQ(where.first_row, first);
        const SensorMeshResult r = mesh_sensor_band(rows_of(g, first, std::min(height, g.rows - first)), {}, 4, where);
        const Mesh& m = r.mesh;
        joined.mesh.positions.insert(joined.mesh.positions.end(), m.positions.begin(), m.positions.end());
        joined.mesh.sensor_positions.insert(joined.mesh.sensor_positions.end(), m.sensor_positions.begin(),
                                            m.sensor_positions.end());
        joined.mesh.times.insert(joined.mesh.times.end(), m.times.begin(), m.times.end());
        joined.mesh.triangles.insert(joined.mesh.triangles.end(), m.triangles.begin(), m.triangles.end());
        joined.mesh.triangle_ids.insert(joined.mesh.triangle_ids.end(), m.triangle_ids.begin(), m.triangle_ids.end());
        joined.face_labels.insert(joined.face_labels.end(), r.face_labels.begin(), r.face_labels.end());
        joined.stats.candidates += r.stats.candidates;
        EXPECT_EQ(where.first_vertex, joined.mesh.positions.size());
      }
      EXPECT_EQ(joined.mesh.positions, whole.mesh.positions) << height;
      EXPECT_EQ(joined.mesh.sensor_positions, whole.mesh.sensor_positions) << height;
      EXPECT_EQ(joined.mesh.times, whole.mesh.times) << height;
      EXPECT_EQ(joined.mesh.triangles, whole.mesh.triangles) << height;
      EXPECT_EQ(joined.mesh.triangle_ids, whole.mesh.triangle_ids) << height;
      EXPECT_EQ(joined.face_labels, whole.face_labels) << height;
      EXPECT_EQ(joined.stats.candidates, whole.stats.candidates) << height;
    }
  }
}

}  // namespace
}  // namespace citymesh
