// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "citymesh/mosaic/mosaic.h"
#include "grid_triangles.h"

namespace citymesh {
namespace {

/// A flat grid of nx x ny cells of size `step` from (x0, 0) at height z.
Mesh grid(float x0, int nx, int ny, float step, float z) {
  return test::placed_grid(nx, ny, [=](int i, int j) { return Vec3f{x0 + float(i) * step, float(j) * step, z}; });
}

/// (t, offset + t) for t < count: the triangles of two like grids paired one to one.
std::vector<TrianglePair> ladder_pairs(std::uint32_t count) {
  std::vector<TrianglePair> pairs;
  for (std::uint32_t t = 0; t < count; ++t) pairs.emplace_back(t, count + t);
  return pairs;
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
  const MosaicInput input{meshes, dates, &change, 0.1, {}};
  std::vector<std::uint8_t> selected(328, 0);
  std::fill(selected.begin(), selected.begin() + 200, 1);
  const std::uint64_t added = fill_holes(input, selected).added;

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

TEST(FillHoles, ConsistentPairsOnlySpareTheSearchAndNeverChangeWhatIsAdded) {
  // The fill looks at a candidate's selected partners before searching around it: whatever
  // pairs are listed (here every pair of triangles of different meshes, near or far, and
  // partners found from either side), it adds exactly what it adds without any.
  const std::vector<Mesh> meshes{grid(0, 10, 10, 0.1f, 0), grid(0.05f, 8, 4, 0.25f, 0.09f),
                                 grid(0.3f, 8, 4, 0.25f, 0.02f)};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(10)), TimePoint(std::chrono::days(20)),
                                     TimePoint(std::chrono::days(1))};
  ChangeResult change;
  change.index.offsets = {0, 200, 264, 328};
  change.kept.assign(328, 1);
  std::vector<std::uint8_t> start(328, 0);
  for (std::size_t g = 0; g < 200; g += 3) start[g] = 1;  // a sparse selection: holes everywhere
  start[210] = start[300] = 1;
  std::vector<std::uint8_t> without = start;
  const std::uint64_t added = fill_holes({meshes, dates, &change, 0.1, {}}, without).added;
  std::vector<TrianglePair> pairs;
  for (std::uint32_t g = 0; g < 328; ++g) {
    for (std::uint32_t u = g + 1; u < 328; ++u) {
      if (change.index.acquisition_of(g) != change.index.acquisition_of(u)) pairs.emplace_back(g, u);
    }
  }
  change.consistent_pairs = std::move(pairs);
  std::vector<std::uint8_t> with = start;
  EXPECT_EQ(fill_holes({meshes, dates, &change, 0.1, {}}, with).added, added);
  EXPECT_EQ(with, without);
  EXPECT_GT(added, 10u);
  EXPECT_LT(added, 328u - 70u) << "some candidates were covered";
}

TEST(FillHoles, NeverAddsWhatTheChangeStepDropped) {
  const std::vector<Mesh> meshes{grid(0, 2, 2, 0.1f, 0), grid(5, 2, 2, 0.1f, 0)};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(1)), TimePoint(std::chrono::days(2))};
  ChangeResult change;
  change.index.offsets = {0, 8, 16};
  change.kept.assign(16, 1);
  std::fill(change.kept.begin() + 8, change.kept.end(), 0);
  std::vector<std::uint8_t> selected(16, 0);
  EXPECT_EQ(fill_holes({meshes, dates, &change, 0.1, {}}, selected).added, 8u);
  for (std::size_t g = 0; g < 16; ++g) EXPECT_EQ(selected[g], g < 8 ? 1 : 0);
}

TEST(ForcedTriangles, AreSelectedAndTheRestAdaptsToThem) {
  // Two grids over the same square, the coarse one overlapping the fine one pair by pair.
  // Free, the mosaic keeps one of them; with the coarse one's left half forced (a neighbouring
  // tile's decision), it keeps that half and takes the fine grid only where nothing is forced.
  const std::vector<Mesh> meshes{grid(0, 4, 4, 0.25f, 0), grid(0, 4, 4, 0.25f, 0.01f)};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(1)), TimePoint(std::chrono::days(40))};
  ChangeResult change;
  change.index.offsets = {0, 32, 64};
  change.kept.assign(64, 1);
  change.consistent_pairs = ladder_pairs(32);
  MosaicParams params;
  params.fill_holes = false;
  // Free, one grid wins whole; the other one's left half is then forced.
  const MosaicSelection free = select_mosaic({meshes, dates, &change, 0.1, {}}, params);
  const std::uint32_t loser = free.selected[0] != 0 ? 1 : 0, winner = 1 - loser;
  std::vector<std::uint8_t> forced(64, 0);
  for (std::uint32_t t = 0; t < 32; ++t) {
    EXPECT_EQ(free.selected[32 * winner + t], 1);
    const auto [a, b, c] = meshes[loser].corners(t);
    if ((a.x + b.x + c.x) / 3.0 < 0.5) forced[32 * loser + t] = 1;
  }
  const MosaicSelection s = select_mosaic({meshes, dates, &change, 0.1, forced}, params);
  std::size_t forced_count = 0;
  for (std::uint32_t t = 0; t < 32; ++t) {
    if (forced[32 * loser + t] != 0) {
      ++forced_count;
      EXPECT_EQ(s.selected[32 * loser + t], 1) << t;
      EXPECT_EQ(s.selected[32 * winner + t], 0) << t << ": its overlapping partner is forced";
    } else {
      EXPECT_EQ(s.selected[t] + s.selected[32 + t], 1) << t << ": exactly one of the pair";
    }
  }
  EXPECT_EQ(forced_count, 16u);
}

}  // namespace
}  // namespace citymesh
