// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
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

TEST(TileGrid, OwnerEqualsTheFloorOfTheDivisionEvenOnTileSides) {
  // owner() multiplies by 1 / tile_size and falls back to the division near a side: compare
  // with the division at points on, and a few units in the last place around, every side.
  std::mt19937 rng(9);
  for (const double size : {50.0, 0.3, 7.7, 1.0 / 3.0, 100.0}) {
    const std::array<double, 2> origin{651000.125, -6860000.3};
    const TileGrid grid({.tile_size = size, .halo = size / 4, .origin = origin});
    std::uniform_int_distribution<int> k(-2000, 2000), step(-4, 4);
    for (int n = 0; n < 20000; ++n) {
      Vec3d p{origin[0] + k(rng) * size, origin[1] + k(rng) * size, 0};
      for (int s = step(rng); s != 0; s += s > 0 ? -1 : 1) p.x = std::nextafter(p.x, s > 0 ? 1e300 : -1e300);
      for (int s = step(rng); s != 0; s += s > 0 ? -1 : 1) p.y = std::nextafter(p.y, s > 0 ? 1e300 : -1e300);
      const TileKey expected{static_cast<std::int32_t>(std::floor((p.x - origin[0]) / size)),
                             static_cast<std::int32_t>(std::floor((p.y - origin[1]) / size))};
      ASSERT_EQ(grid.owner(p), expected) << "size " << size << " at " << p.x << ", " << p.y;
    }
  }
}

TEST(TileGrid, HaloTilesEqualBruteForce) {
  const TileGrid grid({.tile_size = 10, .halo = 1.5, .origin = {0, 0}});
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-30, 30), e(0, 3);
  std::size_t within = 0;
  for (int n = 0; n < 2000; ++n) {
    Box3d box;
    const Vec3d a{u(rng), u(rng), 0};
    box.extend(a);
    box.extend(a + Vec3d{e(rng), e(rng), 1});
    const TileKey owner = grid.owner(a);
    std::vector<TileKey> expected;
    std::size_t bands_met = 0;
    for (int i = -5; i <= 5; ++i) {
      for (int j = -5; j <= 5; ++j) {
        const double x0 = i * 10 - 1.5, x1 = (i + 1) * 10 + 1.5, y0 = j * 10 - 1.5, y1 = (j + 1) * 10 + 1.5;
        const bool meets = box.min.x < x1 && box.max.x >= x0 && box.min.y < y1 && box.max.y >= y0;
        bands_met += meets ? 1 : 0;
        if (meets && TileKey{i, j} != owner) expected.push_back({i, j});
      }
    }
    ASSERT_EQ(grid.halo_tiles(box, owner), expected) << n;
    // The tiler's shortcut: one tile's band holds the box exactly when no other band meets it.
    ASSERT_EQ(grid.within_one_tile(box), bands_met == 1) << n;
    within += bands_met == 1 ? 1 : 0;
  }
  EXPECT_GT(within, 200u);  // both answers occur
  EXPECT_LT(within, 1800u);
}

/// copy_targets as the tiler had it: halo_tiles, then tiles_crossed less the owner and the
/// halo tiles, nothing when the whole shape lies within one tile.
void reference_targets(const TileGrid& grid, const std::array<Vec3d, 3>& c, const Vec3d& viewpoint, TileKey owner,
                       std::vector<TileKey>& halo, std::vector<TileKey>& crossed) {
  halo.clear();
  crossed.clear();
  Box3d box, reach;
  for (const Vec3d& p : c) box.extend(p);
  reach = box;
  reach.extend(viewpoint);
  if (grid.within_one_tile(reach)) return;
  halo = grid.halo_tiles(box, owner);
  const std::array<Vec3d, 4> tetrahedron{c[0], c[1], c[2], viewpoint};
  for (const TileKey k : grid.tiles_crossed(tetrahedron)) {
    if (k != owner && !std::binary_search(halo.begin(), halo.end(), k)) crossed.push_back(k);
  }
}

TEST(TileGrid, CopyTargetsEqualHaloAndCrossedTilesOnTileSidesAtCityCoordinates) {
  // Lambert-93 sized coordinates, and triangles whose grown box falls exactly on a tile side
  // or an ulp either way: where the quick comparisons must hand over to the cells.
  const TileGrid grid({.tile_size = 50, .halo = 2, .origin = {650000.5, 6860000.25}});
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> tile(-3, 3), offset(-2, 2);
  std::uniform_real_distribution<double> u(0, 50), e(0, 5), far(-30, 30);
  std::vector<TileKey> halo, crossed, expected_halo, expected_crossed;
  std::size_t none = 0, with_crossed = 0;
  for (int n = 0; n < 20000; ++n) {
    const Vec3d corner = grid.corner({tile(rng), tile(rng)});
    const auto near_side = [&](double side) {
      double x = side;
      for (int k = offset(rng); k != 0; k += k > 0 ? -1 : 1) x = std::nextafter(x, k > 0 ? 1e300 : -1e300);
      return x;
    };
    Vec3d a{corner.x + u(rng), corner.y + u(rng), 0};
    if (n % 2 == 0) a.x = near_side(corner.x + 2);  // grown lower side on the tile's side
    if (n % 3 == 0) a.y = near_side(corner.y + 2);
    Vec3d b = a + Vec3d{e(rng), 0, 1}, c = a + Vec3d{0, e(rng), 2};
    if (n % 5 == 0) b.x = near_side(corner.x + 48);  // grown upper side on the next tile's
    const std::array<Vec3d, 3> t{a, b, c};
    // The viewpoint near the triangle, or far enough to cross tiles.
    const Vec3d viewpoint = n % 4 == 0 ? a + Vec3d{far(rng), far(rng), 2} : a + Vec3d{0.5, 0.5, 2};
    const TileKey owner = grid.owner((a + b + c) / 3.0);
    grid.copy_targets(t, viewpoint, owner, halo, crossed);
    reference_targets(grid, t, viewpoint, owner, expected_halo, expected_crossed);
    ASSERT_EQ(halo, expected_halo) << n;
    ASSERT_EQ(crossed, expected_crossed) << n;
    none += halo.empty() && crossed.empty() ? 1 : 0;
    with_crossed += crossed.empty() ? 0 : 1;
  }
  EXPECT_GT(none, 1000u);  // every kind of answer occurs
  EXPECT_GT(with_crossed, 1000u);
  EXPECT_LT(none, 19000u);
}

TEST(TileGrid, ATriangleInATilesInteriorIsOwnedThereAndCopiedNowhereElse) {
  // The tiler places a triangle with interior(key).holds() alone, keeping the last owner's
  // interior: at city coordinates, with grown boxes on a tile side or an ulp either way, a
  // triangle the interior holds must have that owner and no halo or crossed tile.
  const TileGrid grid({.tile_size = 50, .halo = 2, .origin = {650000.5, 6860000.25}});
  EXPECT_FALSE(TileInterior{}.holds(Box3d{{0, 0, 0}, {0, 0, 0}}));  // the tiler's start
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> tile(-3, 3), offset(-2, 2), neighbour(-1, 1);
  std::uniform_real_distribution<double> u(0, 50), e(0, 5), near(-3, 3);
  std::size_t held = 0, refused = 0;
  for (int n = 0; n < 20000; ++n) {
    const TileKey key{tile(rng), tile(rng)};
    const Vec3d corner = grid.corner(key);
    const auto near_side = [&](double side) {
      double x = side;
      for (int k = offset(rng); k != 0; k += k > 0 ? -1 : 1) x = std::nextafter(x, k > 0 ? 1e300 : -1e300);
      return x;
    };
    Vec3d a{corner.x + u(rng), corner.y + u(rng), 0};
    if (n % 2 == 0) a.x = near_side(corner.x + 2);
    if (n % 3 == 0) a.y = near_side(corner.y + 48);
    const Vec3d b = a + Vec3d{e(rng), 0, 1}, c = a + Vec3d{0, e(rng), 2};
    const Vec3d viewpoint = n % 5 == 0 ? a : a + Vec3d{near(rng), near(rng), 2};
    Box3d box, reach;
    for (const Vec3d& p : {a, b, c}) box.extend(p);
    reach = box;
    reach.extend(viewpoint);
    // The interior of the triangle's tile or of a neighbour, as the last owner may be.
    const TileInterior interior = grid.interior({key.i + neighbour(rng) * (n % 7 == 0), key.j});
    if (!interior.holds(reach)) {
      ++refused;
      continue;
    }
    ++held;
    ASSERT_EQ(grid.owner((a + b + c) / 3.0), interior.key) << n;
    EXPECT_TRUE(grid.halo_tiles(box, interior.key).empty()) << n;
    const std::array<Vec3d, 4> tetrahedron{a, b, c, viewpoint};
    EXPECT_EQ(grid.tiles_crossed(tetrahedron), std::vector<TileKey>{interior.key}) << n;
  }
  EXPECT_GT(held, 3000u);  // both answers occur
  EXPECT_GT(refused, 3000u);
}

/// Brute force: two convex sets in the plane meet when a point of one lies in the other or
/// two of their segments cross. The hull of four points is the union of the four triangles.
bool point_in_triangle(double px, double py, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const auto side = [&](const Vec3d& u, const Vec3d& v) { return (v.x - u.x) * (py - u.y) - (v.y - u.y) * (px - u.x); };
  const double s0 = side(a, b), s1 = side(b, c), s2 = side(c, a);
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

bool segment_meets_rectangle(const Vec3d& a, const Vec3d& b, double x0, double y0, double x1, double y1) {
  double t0 = 0, t1 = 1;  // Liang-Barsky clipping
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double p[4] = {-dx, dx, -dy, dy}, q[4] = {a.x - x0, x1 - a.x, a.y - y0, y1 - a.y};
  for (int k = 0; k < 4; ++k) {
    if (p[k] == 0) {
      if (q[k] < 0) return false;
    } else if (p[k] < 0) {
      t0 = std::max(t0, q[k] / p[k]);
    } else {
      t1 = std::min(t1, q[k] / p[k]);
    }
  }
  return t0 <= t1;
}

bool hull_meets_rectangle_brute(const std::array<Vec3d, 4>& pts, double x0, double y0, double x1, double y1) {
  for (std::size_t a = 0; a < 4; ++a) {
    for (std::size_t b = a + 1; b < 4; ++b) {
      if (segment_meets_rectangle(pts[a], pts[b], x0, y0, x1, y1)) return true;
    }
  }
  for (const double cx : {x0, x1}) {
    for (const double cy : {y0, y1}) {
      for (std::size_t skip = 0; skip < 4; ++skip) {
        std::array<Vec3d, 3> t;
        for (std::size_t k = 0, n = 0; k < 4; ++k) if (k != skip) t[n++] = pts[k];
        if (point_in_triangle(cx, cy, t[0], t[1], t[2])) return true;
      }
    }
  }
  return false;
}

TEST(TileGrid, TilesCrossedByATetrahedronEqualBruteForce) {
  const TileGrid grid({.tile_size = 10, .halo = 1.5, .origin = {0, 0}});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-20, 20), near(-1, 1), far(-25, 25);
  std::size_t strictly_fewer = 0;
  for (int n = 0; n < 3000; ++n) {
    // A small triangle and a viewpoint up to 25 m away: long thin slivers, like MLS.
    const Vec3d a{u(rng), u(rng), 0};
    const std::array<Vec3d, 4> pts{a, a + Vec3d{near(rng), near(rng), 1}, a + Vec3d{near(rng), near(rng), 0},
                                   a + Vec3d{far(rng), far(rng), 2}};
    std::vector<TileKey> expected;
    std::size_t in_box = 0;
    for (int i = -8; i <= 8; ++i) {
      for (int j = -8; j <= 8; ++j) {
        const double x0 = i * 10 - 1.5, x1 = (i + 1) * 10 + 1.5, y0 = j * 10 - 1.5, y1 = (j + 1) * 10 + 1.5;
        Box3d box;
        for (const Vec3d& p : pts) box.extend(p);
        if (box.min.x <= x1 && box.max.x >= x0 && box.min.y <= y1 && box.max.y >= y0) ++in_box;
        if (hull_meets_rectangle_brute(pts, x0, y0, x1, y1)) expected.push_back({i, j});
      }
    }
    ASSERT_EQ(grid.tiles_crossed(pts), expected) << n;
    if (expected.size() < in_box) ++strictly_fewer;
  }
  EXPECT_GT(strictly_fewer, 300u);  // the exact test matters: bounding boxes would add tiles
}

TEST(TileGrid, RefusesBadSizes) {
  EXPECT_THROW(TileGrid({.tile_size = 0, .halo = 0, .origin = {0, 0}}), ConfigError);
  EXPECT_THROW(TileGrid({.tile_size = 10, .halo = 5, .origin = {0, 0}}), ConfigError);
}

}  // namespace
}  // namespace citymesh
