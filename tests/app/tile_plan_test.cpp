// SPDX-License-Identifier: MIT
// Which tiles wait for which, and subsets: against brute force on random tile sets.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "citymesh/core/error.h"
#include "tile_job.h"
#include "tile_plan.h"

namespace citymesh::app {
namespace {

/// A store of random tiles on a w x h grid (some cells empty) with random triangle counts.
TileStore random_store(std::mt19937& rng, int w, int h) {
  TileStore store;
  store.triangles = {0};
  for (int i = -1; i < w - 1; ++i) {
    for (int j = -2; j < h - 2; ++j) {
      if (rng() % 4 == 0) continue;
      const std::uint64_t owned = 1 + rng() % 1000, halo = rng() % 200;
      store.tiles.push_back({{i, j}, {{owned, halo, 0}}, {}});
      store.triangles[0] += owned;
    }
  }
  return store;
}

TEST(TilePlan, DependenciesAreTheEarlierPhaseNeighbours) {
  std::mt19937 rng(3);
  const TileStore store = random_store(rng, 7, 6);
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    std::vector<std::size_t> expected;
    const TileKey a = store.tiles[k].key;
    for (std::size_t d = 0; d < store.tiles.size(); ++d) {
      const TileKey b = store.tiles[d].key;
      const bool touches = d != k && std::abs(a.i - b.i) <= 1 && std::abs(a.j - b.j) <= 1;
      if (touches && tile_phase(b) < tile_phase(a)) expected.push_back(d);
    }
    EXPECT_EQ(tile_dependencies(store, k), expected) << a.name();
  }
}

TEST(TilePlan, SubsetsSplitTheTilesOnceWithBalancedCost) {
  std::mt19937 rng(5);
  const TileStore store = random_store(rng, 12, 9);
  std::uint64_t total = 0, largest = 0;
  for (const auto& t : store.tiles) {
    total += t.total();
    largest = std::max(largest, t.total());
  }
  for (const std::size_t n : {1u, 2u, 3u, 7u}) {
    std::vector<int> owners(store.tiles.size(), 0);
    for (std::size_t i = 1; i <= n; ++i) {
      const std::vector<std::size_t> tiles = subset_tiles(store, {i, n});
      std::uint64_t cost = 0;
      for (const std::size_t k : tiles) {
        ++owners[k];
        cost += store.tiles[k].total();
      }
      // Each share is within one tile of an equal split.
      EXPECT_NEAR(static_cast<double>(cost), static_cast<double>(total) / static_cast<double>(n),
                  static_cast<double>(largest))
          << i << "/" << n;
      // Consecutive in key order.
      for (std::size_t x = 1; x < tiles.size(); ++x) EXPECT_EQ(tiles[x], tiles[x - 1] + 1);
    }
    for (std::size_t k = 0; k < owners.size(); ++k) EXPECT_EQ(owners[k], 1) << "tile " << k << " with " << n;
  }
  // More subsets than tiles: some are empty, none overlaps.
  const std::size_t many = store.tiles.size() + 5;
  std::size_t covered = 0;
  for (std::size_t i = 1; i <= many; ++i) covered += subset_tiles(store, {i, many}).size();
  EXPECT_EQ(covered, store.tiles.size());
}

TEST(TilePlan, WithDependenciesIsTheSmallestClosedSet) {
  std::mt19937 rng(9);
  const TileStore store = random_store(rng, 10, 8);
  const std::vector<std::size_t> own = subset_tiles(store, {2, 4});
  const std::vector<std::size_t> needed = with_dependencies(store, own);
  const std::set<std::size_t> in(needed.begin(), needed.end());
  for (const std::size_t k : own) EXPECT_TRUE(in.contains(k));
  for (const std::size_t k : needed) {
    for (const std::size_t d : tile_dependencies(store, k)) EXPECT_TRUE(in.contains(d)) << "not closed";
  }
  // Smallest: every added tile is reachable from an own tile (brute-force fixpoint).
  std::set<std::size_t> reach(own.begin(), own.end());
  for (bool grew = true; grew;) {
    grew = false;
    for (const std::size_t k : std::set<std::size_t>(reach)) {
      for (const std::size_t d : tile_dependencies(store, k)) grew = reach.insert(d).second || grew;
    }
  }
  EXPECT_EQ(in, reach);
  EXPECT_GT(needed.size(), own.size());  // a strip in the middle waits for its neighbours
}

TEST(TilePlan, SubsetParsing) {
  const Subset s = Subset::parse("2/8");
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 8u);
  EXPECT_EQ(s.name(), "2/8");
  for (const char* bad : {"0/3", "4/3", "3", "/3", "1/", "a/3", "1/0", "1/3x", "-1/3"}) {
    EXPECT_THROW((void)Subset::parse(bad), UsageError) << bad;
  }
}

TEST(TilePlan, TilesOverBudgetAreTheOnesTheBudgetCannotHoldLargestFirst) {
  std::mt19937 rng(5);
  const TileStore store = random_store(rng, 9, 8);
  std::vector<std::size_t> all(store.tiles.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = k;
  // Budgets that hold every tile, none, and about half of them.
  for (const std::uint64_t triangles : {std::uint64_t{1200}, std::uint64_t{0}, std::uint64_t{600}}) {
    const std::uint64_t budget = triangles * kBytesPerTileTriangle;
    const std::vector<std::size_t> over = tiles_over_budget(store, all, budget);
    std::set<std::size_t> expected;
    for (std::size_t k = 0; k < all.size(); ++k) {
      if (store.tiles[k].total() * kBytesPerTileTriangle > budget) expected.insert(k);
    }
    EXPECT_EQ(std::set<std::size_t>(over.begin(), over.end()), expected) << "budget for " << triangles;
    EXPECT_EQ(over.size(), expected.size());
    for (std::size_t n = 1; n < over.size(); ++n) {
      EXPECT_GE(store.tiles[over[n - 1]].total(), store.tiles[over[n]].total());
    }
  }
  // Only the tiles asked about.
  const std::vector<std::size_t> first_three{0, 1, 2};
  for (const std::size_t k : tiles_over_budget(store, first_three, 0)) EXPECT_LT(k, 3u);
  EXPECT_EQ(tiles_over_budget(store, first_three, 0).size(), 3u);
}

}  // namespace
}  // namespace citymesh::app
