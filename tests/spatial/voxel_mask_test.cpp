// SPDX-License-Identifier: MIT
// The voxel mask against a plain set of voxels.
#include "citymesh/spatial/voxel_mask.h"

#include <gtest/gtest.h>

#include <random>
#include <set>
#include <tuple>

namespace citymesh {
namespace {

using Voxel = std::tuple<int, int, int>;

VoxelBox random_box(std::mt19937& rng, int lo, int hi, int largest) {
  std::uniform_int_distribution<int> corner(lo, hi), size(0, largest);
  VoxelBox b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = corner(rng);
    b.hi[a] = b.lo[a] + size(rng);
  }
  return b;
}

bool brute_force_any_in(const std::set<Voxel>& voxels, const VoxelBox& b) {
  for (const auto& [x, y, z] : voxels) {
    if (x >= b.lo[0] && x <= b.hi[0] && y >= b.lo[1] && y <= b.hi[1] && z >= b.lo[2] && z <= b.hi[2]) return true;
  }
  return false;
}

TEST(VoxelMask, AnswersLikeTheSetOfItsBoxesVoxels) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    // Negative and positive voxels, boxes of 1 to 12 voxels a side across block edges.
    std::vector<VoxelBox> boxes;
    std::set<Voxel> voxels;
    for (int i = 0; i < 40; ++i) {
      boxes.push_back(random_box(rng, -30, 30, trial % 2 == 0 ? 2 : 11));
      const VoxelBox& b = boxes.back();
      for (int x = b.lo[0]; x <= b.hi[0]; ++x)
        for (int y = b.lo[1]; y <= b.hi[1]; ++y)
          for (int z = b.lo[2]; z <= b.hi[2]; ++z) voxels.insert({x, y, z});
    }
    const VoxelMask mask(boxes);
    ASSERT_FALSE(mask.holds_everything());
    int hits = 0;
    for (int q = 0; q < 400; ++q) {
      const VoxelBox query = random_box(rng, -45, 45, q % 3 == 0 ? 9 : 1);
      const bool expected = brute_force_any_in(voxels, query);
      ASSERT_EQ(mask.any_in(query), expected) << "trial " << trial << " query " << q;
      hits += expected ? 1 : 0;
    }
    EXPECT_GT(hits, 0);
    EXPECT_LT(hits, 400);
  }
}

TEST(VoxelMask, HoldsNothingWithoutBoxesAndEverythingWhenItsIndexWouldBeTooLarge) {
  const VoxelMask empty(std::span<const VoxelBox>{});
  EXPECT_FALSE(empty.any_in({{0, 0, 0}, {100, 100, 100}}));
  const VoxelMask all;
  EXPECT_TRUE(all.any_in({{5, 5, 5}, {5, 5, 5}}));
  // Two voxels 8192 apart: an index of 1025 blocks along x.
  const std::vector<VoxelBox> far{{{-4096, 0, 0}, {-4096, 0, 0}}, {{4096, 0, 0}, {4096, 0, 0}}};
  const VoxelMask scattered(far, 1024);
  EXPECT_TRUE(scattered.holds_everything());
  EXPECT_TRUE(scattered.any_in({{7, 7, 7}, {7, 7, 7}}));
  const VoxelMask allowed(far, 1025);
  EXPECT_FALSE(allowed.holds_everything());
  EXPECT_EQ(allowed.blocks(), 2u);
  EXPECT_TRUE(allowed.any_in({{4090, -3, -3}, {4100, 0, 0}}));
  EXPECT_FALSE(allowed.any_in({{7, 0, 0}, {4095, 0, 0}}));
  // Voxels near the int32 limits: no overflow in the block arithmetic.
  const std::vector<VoxelBox> edge{{{INT32_MAX - 3, INT32_MIN, 0}, {INT32_MAX, INT32_MIN + 2, 0}}};
  const VoxelMask at_edge(edge);
  EXPECT_TRUE(at_edge.any_in({{INT32_MAX, INT32_MIN, 0}, {INT32_MAX, INT32_MIN, 0}}));
  EXPECT_FALSE(at_edge.any_in({{INT32_MAX - 8, INT32_MIN, 0}, {INT32_MAX - 4, INT32_MIN, 0}}));
}

}  // namespace
}  // namespace citymesh
