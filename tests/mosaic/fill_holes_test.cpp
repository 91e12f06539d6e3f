// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "citymesh/mosaic/mosaic.h"

namespace citymesh {
namespace {

/// A flat grid of nx x ny cells of size `step` from (x0, 0) at height z.
Mesh grid(float x0, int nx, int ny, float step, float z) {
  Mesh m;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) m.positions.push_back({x0 + float(i) * step, float(j) * step, z});
  }
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  m.triangle_ids.resize(m.triangles.size());
  return m;
}

TEST(FillHoles, AddsNewestTrianglesWhereNothingSelectedIsNear) {
  // Acquisition 0 (selected) covers x in [0, 1]; 1 (newest) and 2 (oldest) both cover
  // [0, 2] more coarsely. The fill must take 1's triangles beyond the reach of 0 and none of 2.
  const std::vector<Mesh> meshes{grid(0, 10, 10, 0.1f, 0), grid(0, 8, 4, 0.25f, 0.01f), grid(0, 8, 4, 0.25f, 0.02f)};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(10)), TimePoint(std::chrono::days(20)),
                                     TimePoint(std::chrono::days(1))};
  ChangeResult change;
  change.index.offsets = {0, 200, 264, 328};
  change.kept.assign(328, 1);
  const MosaicInput input{meshes, dates, &change, 0.1};
  std::vector<std::uint8_t> selected(328, 0);
  std::fill(selected.begin(), selected.begin() + 200, 1);
  const std::uint64_t added = fill_holes(input, selected);

  std::uint64_t expected = 0;
  for (std::size_t t = 0; t < 64; ++t) {
    const auto [a, b, c] = meshes[1].corners(t);
    const Vec3d p = (a + b + c) / 3.0;
    // Distance from the centroid to the square [0,1]^2 at z = 0 (where acquisition 0 lies).
    const double dx = std::max(0.0, p.x - 1.0), dy = std::max(0.0, p.y - 1.0);
    const bool far = std::sqrt(dx * dx + dy * dy + p.z * p.z) > 0.1;
    EXPECT_EQ(selected[200 + t], far ? 1 : 0) << "triangle " << t;
    expected += far ? 1 : 0;
  }
  EXPECT_GT(expected, 20u);
  EXPECT_EQ(added, expected);
  for (std::size_t g = 264; g < 328; ++g) EXPECT_EQ(selected[g], 0) << "the oldest fills nothing left";
}

TEST(FillHoles, NeverAddsWhatTheChangeStepDropped) {
  const std::vector<Mesh> meshes{grid(0, 2, 2, 0.1f, 0), grid(5, 2, 2, 0.1f, 0)};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(1)), TimePoint(std::chrono::days(2))};
  ChangeResult change;
  change.index.offsets = {0, 8, 16};
  change.kept.assign(16, 1);
  std::fill(change.kept.begin() + 8, change.kept.end(), 0);
  std::vector<std::uint8_t> selected(16, 0);
  EXPECT_EQ(fill_holes({meshes, dates, &change, 0.1}, selected), 8u);
  for (std::size_t g = 0; g < 16; ++g) EXPECT_EQ(selected[g], g < 8 ? 1 : 0);
}

}  // namespace
}  // namespace citymesh
