// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <random>

#include "citymesh/core/error.h"
#include "citymesh/tiler/tile_grid.h"

namespace citymesh {
namespace {

TEST(TileGrid, EveryPointHasExactlyTheOwnerWhoseSquareContainsIt) {
  const TileGrid grid({.tile_size = 50, .halo = 2, .origin = {651000, 6860000}});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(650800, 651300), y(6859800, 6860300);
  for (int i = 0; i < 10000; ++i) {
    const Vec3d p{x(rng), y(rng), 40};
    const TileKey k = grid.owner(p);
    const Vec3d c = grid.corner(k);
    ASSERT_LE(c.x, p.x);
    ASSERT_LT(p.x, c.x + 50);
    ASSERT_LE(c.y, p.y);
    ASSERT_LT(p.y, c.y + 50);
  }
  EXPECT_EQ(grid.owner({651000, 6860000, 0}), (TileKey{0, 0}));
  EXPECT_EQ(grid.owner({650999.999, 6860000, 0}), (TileKey{-1, 0}));
  EXPECT_EQ((TileKey{12, -4}).name(), "12_-4");
}

TEST(TileGrid, HaloTilesEqualBruteForce) {
  const TileGrid grid({.tile_size = 10, .halo = 1.5, .origin = {0, 0}});
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-30, 30), e(0, 3);
  for (int n = 0; n < 2000; ++n) {
    Box3d box;
    const Vec3d a{u(rng), u(rng), 0};
    box.extend(a);
    box.extend(a + Vec3d{e(rng), e(rng), 1});
    const TileKey owner = grid.owner(a);
    std::vector<TileKey> expected;
    for (int i = -5; i <= 5; ++i) {
      for (int j = -5; j <= 5; ++j) {
        const double x0 = i * 10 - 1.5, x1 = (i + 1) * 10 + 1.5, y0 = j * 10 - 1.5, y1 = (j + 1) * 10 + 1.5;
        const bool meets = box.min.x < x1 && box.max.x >= x0 && box.min.y < y1 && box.max.y >= y0;
        if (meets && TileKey{i, j} != owner) expected.push_back({i, j});
      }
    }
    ASSERT_EQ(grid.halo_tiles(box, owner), expected) << n;
  }
}

TEST(TileGrid, RefusesBadSizes) {
  EXPECT_THROW(TileGrid({.tile_size = 0, .halo = 0, .origin = {0, 0}}), ConfigError);
  EXPECT_THROW(TileGrid({.tile_size = 10, .halo = 5, .origin = {0, 0}}), ConfigError);
}

}  // namespace
}  // namespace citymesh
