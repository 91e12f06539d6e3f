// SPDX-License-Identifier: MIT
#include "citymesh/spatial/occupancy_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

namespace citymesh {
namespace {

using Voxel = std::tuple<int, int, int>;

Voxel voxel(const Vec3f& p, double s) {
  return {int(std::floor(p.x / s)), int(std::floor(p.y / s)), int(std::floor(p.z / s))};
}

/// Brute force: whether any voxel of `reference` lies in the voxels of [lo, hi].
bool reference_any_in(const std::set<Voxel>& reference, const Vec3f& lo, const Vec3f& hi, double s) {
  const auto [i0, j0, k0] = voxel(lo, s);
  const auto [i1, j1, k1] = voxel(hi, s);
  return std::any_of(reference.begin(), reference.end(), [&](const Voxel& v) {
    const auto [a, b, c] = v;
    return a >= i0 && a <= i1 && b >= j0 && b <= j1 && c >= k0 && c <= k1;
  });
}

TEST(OccupancyGrid, MarksAndQueriesLikeAVoxelSet) {
  const double s = 0.25;
  OccupancyGrid grid(s);
  std::set<Voxel> reference;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-20.f, 20.f);
  for (int i = 0; i < 300; ++i) {
    const Vec3f p{u(rng), u(rng), u(rng)};
    grid.mark_point(p);
    reference.insert(voxel(p, s));
  }
  for (int i = 0; i < 20; ++i) {
    const Vec3f lo{u(rng), u(rng), u(rng)};
    const Vec3f hi = lo + Vec3f{0.6f, 0.3f, 1.1f};
    grid.mark_box(lo, hi);
    const auto [i0, j0, k0] = voxel(lo, s);
    const auto [i1, j1, k1] = voxel(hi, s);
    for (int a = i0; a <= i1; ++a)
      for (int b = j0; b <= j1; ++b)
        for (int c = k0; c <= k1; ++c) reference.insert({a, b, c});
  }
  EXPECT_EQ(grid.marked_voxels(), reference.size());
  for (int i = 0; i < 3000; ++i) {
    const Vec3f p{u(rng), u(rng), u(rng)};
    ASSERT_EQ(grid.occupied(p), reference.count(voxel(p, s)) == 1);
  }
  // A reader keeps its node cache from one query to the next: the same answers.
  OccupancyGrid::Reader reader(grid);
  for (int i = 0; i < 500; ++i) {
    const Vec3f lo{u(rng), u(rng), u(rng)};
    const float e = i % 10 == 0 ? 8.f : 0.7f;  // some boxes take the sparse query path
    const Vec3f hi = lo + Vec3f{e, e, e};
    const bool expected = reference_any_in(reference, lo, hi, s);
    ASSERT_EQ(grid.any_in_box(lo, hi), expected) << i;
    ASSERT_EQ(reader.any_in_box(lo, hi), expected) << i;
  }
}

/// Marks the voxels of [lo, hi] in the reference set.
void mark_reference(const Vec3f& lo, const Vec3f& hi, double s, std::set<Voxel>& reference) {
  const auto [i0, j0, k0] = voxel(lo, s);
  const auto [i1, j1, k1] = voxel(hi, s);
  for (int a = i0; a <= i1; ++a)
    for (int b = j0; b <= j1; ++b)
      for (int c = k0; c <= k1; ++c) reference.insert({a, b, c});
}

/// Boxes marked in a grid and in its reference set: `large_count` of extent `large`, then
/// `small_count` of random extent up to `small`, their corners in [-corner, corner].
struct RandomBoxes {
  float corner = 0;
  Vec3f large;
  int large_count = 0;
  float small = 0;
  int small_count = 0;
};

void mark_random_boxes(const RandomBoxes& boxes, std::mt19937& rng, OccupancyGrid& grid, std::set<Voxel>& reference) {
  std::uniform_real_distribution<float> corner(-boxes.corner, boxes.corner), extent(0.f, boxes.small);
  for (int i = 0; i < boxes.large_count + boxes.small_count; ++i) {
    const Vec3f lo{corner(rng), corner(rng), corner(rng)};
    const Vec3f hi = lo + (i < boxes.large_count ? boxes.large : Vec3f{extent(rng), extent(rng), extent(rng)});
    grid.mark_box(lo, hi);
    mark_reference(lo, hi, grid.voxel_size(), reference);
  }
}

TEST(OccupancyGrid, SmallBoxesAcrossLeavesAndInsideFilledRegionsMarkExactlyTheirVoxels) {
  // Voxels of 1 m: leaves of 8 voxels start at multiples of 8, so boxes of 1 to 4 voxels
  // around +-8 and +-16 straddle leaves on every axis, on both sides of zero. Large boxes go
  // through the sparse fill first, which may leave whole active tiles under later small boxes.
  const double s = 1.0;
  OccupancyGrid grid(s);
  std::set<Voxel> reference;
  std::mt19937 rng(21);
  mark_random_boxes({.corner = 18.f, .large = {9.f, 17.f, 8.5f}, .large_count = 4, .small = 3.5f, .small_count = 3000},
                    rng, grid, reference);  // large: > 64 voxels, the fill
  EXPECT_EQ(grid.marked_voxels(), reference.size());
  for (int a = -20; a <= 24; ++a)
    for (int b = -20; b <= 24; ++b)
      for (int c = -20; c <= 24; ++c) {
        const Vec3f centre{float(a) + 0.5f, float(b) + 0.5f, float(c) + 0.5f};
        ASSERT_EQ(grid.occupied(centre), reference.count({a, b, c}) == 1) << a << " " << b << " " << c;
      }
}

TEST(OccupancyGrid, LargeBoxQueriesAnswerLikeTheVoxelSetOverVoxelsAndActiveTiles) {
  // Queries above the dense limit (16^3 voxels) descend the tree: against a brute-force
  // search of the marked voxels, with whole filled leaves (active tiles) among them, boxes
  // that meet only a tile, only loose voxels, or nothing.
  const double s = 0.5;
  OccupancyGrid grid(s);
  std::set<Voxel> reference;
  std::mt19937 rng(33);
  mark_random_boxes({.corner = 60.f, .large = {10.f, 6.f, 9.f}, .large_count = 6, .small = 1.f, .small_count = 200},
                    rng, grid, reference);  // large: spans whole 8^3 leaves, tiles
  std::uniform_real_distribution<float> corner(-60.f, 60.f);
  std::uniform_real_distribution<float> size(8.5f, 30.f);
  int hits = 0;
  for (int i = 0; i < 400; ++i) {
    const Vec3f lo{corner(rng), corner(rng), corner(rng)};
    const Vec3f hi = lo + Vec3f{size(rng), size(rng), size(rng)};
    const bool expected = reference_any_in(reference, lo, hi, s);
    hits += expected ? 1 : 0;
    ASSERT_EQ(grid.any_in_box(lo, hi), expected) << i;
  }
  EXPECT_GT(hits, 40);
  EXPECT_LT(hits, 360);
  // A box of 20^3 voxels well inside a filled block of 40^3 meets whole filled leaves only:
  // the fill made them active tiles, which count as marked voxels.
  OccupancyGrid filled(s);
  filled.mark_box({0.1f, 0.1f, 0.1f}, {19.9f, 19.9f, 19.9f});
  EXPECT_TRUE(filled.any_in_box({5.1f, 5.1f, 5.1f}, {14.9f, 14.9f, 14.9f}));
  EXPECT_FALSE(filled.any_in_box({25.1f, 5.1f, 5.1f}, {34.9f, 14.9f, 14.9f}));
}

TEST(OccupancyGrid, MergeIsTheUnionAndRepeatedBoxesStayMarked) {
  OccupancyGrid a(0.5), b(0.5);
  a.mark_box({0, 0, 0}, {0.9f, 0.4f, 0.4f});     // 2 voxels
  a.mark_box({0, 0, 0}, {0.9f, 0.4f, 0.4f});     // the same box again: skipped, still 2
  b.mark_box({0.6f, 0, 0}, {1.4f, 0.4f, 0.4f});  // 2 voxels, one shared with a
  b.mark_point({-3, -3, -3});
  a.merge(std::move(b));
  EXPECT_EQ(a.marked_voxels(), 4u);
  EXPECT_TRUE(a.occupied({1.2f, 0.1f, 0.1f}));
  EXPECT_TRUE(a.occupied({-2.9f, -2.9f, -2.9f}));
  EXPECT_EQ(b.marked_voxels(), 0u);  // NOLINT(bugprone-use-after-move): merge leaves it empty
  OccupancyGrid c(1.0);
  EXPECT_ANY_THROW(a.merge(std::move(c)));
}

TEST(OccupancyGrid, RefusesNonPositiveVoxelSize) {
  EXPECT_ANY_THROW(OccupancyGrid(0.0));
  EXPECT_ANY_THROW(OccupancyGrid(-1.0));
}

}  // namespace
}  // namespace citymesh
