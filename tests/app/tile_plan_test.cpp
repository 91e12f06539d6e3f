// SPDX-License-Identifier: MIT
// Which tiles wait for which, and subsets: against brute force on random tile sets.
#include "tile_plan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "citymesh/core/error.h"
#include "tile_job.h"
#include "work_schedule.h"

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
  for (const std::size_t n : {1u, 2u, 3u, 7u, 16u}) {
    std::vector<int> owners(store.tiles.size(), 0);
    // Each halving misses its share by at most half a tile, and the errors add up along the
    // ceil(log2 n) halvings.
    const double levels = std::ceil(std::log2(static_cast<double>(n)));
    for (std::size_t i = 1; i <= n; ++i) {
      const std::vector<std::size_t> tiles = subset_tiles(store, {i, n});
      std::uint64_t cost = 0;
      for (const std::size_t k : tiles) {
        ++owners[k];
        cost += store.tiles[k].total();
      }
      EXPECT_NEAR(static_cast<double>(cost), static_cast<double>(total) / static_cast<double>(n),
                  std::max(1.0, levels) * static_cast<double>(largest))
          << i << "/" << n;
      EXPECT_TRUE(std::is_sorted(tiles.begin(), tiles.end()));
      EXPECT_EQ(tiles, all_subsets(store, n)[i - 1]);
    }
    for (std::size_t k = 0; k < owners.size(); ++k) EXPECT_EQ(owners[k], 1) << "tile " << k << " with " << n;
  }
  // Any subset count is worked out alone, at once (no list of every subset is made).
  const std::size_t huge = std::size_t{1} << 40;
  EXPECT_LE(subset_tiles(store, {huge / 3, huge}).size(), 1u);
  // More subsets than tiles: some are empty, none overlaps.
  const std::size_t many = store.tiles.size() + 5;
  std::size_t covered = 0;
  for (std::size_t i = 1; i <= many; ++i) covered += subset_tiles(store, {i, many}).size();
  EXPECT_EQ(covered, store.tiles.size());
}

/// Tiles every subset must process besides its own (those it waits for, transitively).
std::size_t redone_tiles(const TileStore& store, const std::vector<std::vector<std::size_t>>& subsets) {
  std::size_t redone = 0;
  for (const auto& own : subsets) redone += with_dependencies(store, own).size() - own.size();
  return redone;
}

/// Column strips of about equal cost: consecutive tiles in key order (the rule before
/// session 55), for comparison.
std::vector<std::vector<std::size_t>> strips(const TileStore& store, std::size_t n) {
  double total = 0;
  for (const auto& t : store.tiles) total += static_cast<double>(t.total());
  std::vector<std::vector<std::size_t>> out(n);
  double before = 0;
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    const auto cost = static_cast<double>(store.tiles[k].total());
    out[std::min(static_cast<std::size_t>((before + cost / 2) / total * static_cast<double>(n)), n - 1)].push_back(k);
    before += cost;
  }
  return out;
}

TEST(TilePlan, CompactSubsetsRedoFewerTilesThanStrips) {
  // A square city of 40 x 40 tiles in 16 subsets: strips 2-3 columns wide each redo a column
  // of their neighbour's; blocks have a shorter border in all (measured: 312 against 469).
  std::mt19937 rng(11);
  const TileStore square = random_store(rng, 40, 40);
  const std::size_t blocks = redone_tiles(square, all_subsets(square, 16));
  const std::size_t columns = redone_tiles(square, strips(square, 16));
  EXPECT_LT(blocks * 4, columns * 3) << blocks << " against " << columns;
  for (const std::size_t n : {2u, 5u, 9u}) {
    EXPECT_LE(redone_tiles(square, all_subsets(square, n)), redone_tiles(square, strips(square, n))) << n;
  }
  // A street (one row of tiles): both cut it across, alike.
  const TileStore street = random_store(rng, 60, 1);
  EXPECT_LE(redone_tiles(street, all_subsets(street, 4)), redone_tiles(street, strips(street, 4)) + 4);
}

TEST(TilePlan, ASubsetTakesEveryReadyTileOfItsOwnBeforeAnyOfAnotherSubsets) {
  std::mt19937 rng(13);
  const TileStore store = random_store(rng, 12, 6);
  const std::vector<std::size_t> own = subset_tiles(store, {2, 3});
  const std::vector<std::size_t> needed = with_dependencies(store, own);
  std::vector<std::uint8_t> theirs(store.tiles.size(), 1);
  for (const std::size_t k : own) theirs[k] = 0;
  std::vector<std::vector<std::size_t>> after;
  for (const std::size_t k : needed) {
    std::vector<std::size_t> positions;
    for (const std::size_t d : tile_dependencies(store, k)) {
      positions.push_back(static_cast<std::size_t>(std::lower_bound(needed.begin(), needed.end(), d) - needed.begin()));
    }
    after.push_back(std::move(positions));
  }
  WorkSchedule schedule(tile_priorities(store, needed, theirs), after, std::vector<std::uint8_t>(needed.size(), 0));
  // One worker: whenever a tile of theirs is taken, no own tile is ready (brute force: not
  // taken yet, every tile it waits for finished).
  std::vector<std::uint8_t> finished(needed.size(), 0);
  const auto own_ready = [&] {
    for (std::size_t x = 0; x < needed.size(); ++x) {
      if (finished[x] != 0 || theirs[needed[x]] != 0) continue;
      if (std::all_of(after[x].begin(), after[x].end(), [&](std::size_t d) { return finished[d] != 0; })) return true;
    }
    return false;
  };
  std::size_t taken = 0, theirs_taken = 0;
  while (const std::optional<std::size_t> item = schedule.take()) {
    if (theirs[needed[*item]] != 0) {
      EXPECT_FALSE(own_ready()) << "tile " << store.tiles[needed[*item]].key.name() << " taken first";
      ++theirs_taken;
    }
    schedule.finish(*item);
    finished[*item] = 1;
    ++taken;
  }
  EXPECT_GT(theirs_taken, 0u);
  EXPECT_EQ(taken, needed.size());
  EXPECT_GT(needed.size(), own.size());
  // Without subsets, the order is by size alone.
  const std::vector<std::uint64_t> plain = tile_priorities(store, needed, {});
  for (std::size_t x = 0; x < needed.size(); ++x) {
    for (std::size_t y = 0; y < needed.size(); ++y) {
      EXPECT_EQ(plain[x] < plain[y], store.tiles[needed[x]].total() < store.tiles[needed[y]].total());
    }
  }
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

TEST(TilePlan, AChangedAcquisitionChangesTheDigestsOfTheTilesItReachesAndOfTheirLaterNeighboursOnly) {
  std::mt19937 rng(11);
  TileStore store = random_store(rng, 12, 10);
  // Acquisition 1 covers the western tiles, as a new pass over part of the city would.
  for (TileContents& t : store.tiles) {
    const std::uint64_t owned = t.key.i < 3 ? 1 + rng() % 50 : 0;
    t.triangles.push_back({owned, owned > 0 ? rng() % 9 : 0, t.key.i == 3 ? rng() % 2 : 0});
  }
  const TileDigests before = tile_digests(store, 7, std::vector<std::uint64_t>{100, 200});
  EXPECT_EQ(tile_digests(store, 7, std::vector<std::uint64_t>{100, 200}).result, before.result);
  const TileDigests after = tile_digests(store, 7, std::vector<std::uint64_t>{100, 201});
  // Brute force: the tiles holding acquisition 1 (their inputs changed), then whatever waits
  // for a changed tile.
  std::set<std::size_t> reached;
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    const auto& counts = store.tiles[k].triangles[1];
    if (counts[0] + counts[1] + counts[2] > 0) reached.insert(k);
  }
  std::set<std::size_t> changed = reached;
  for (bool grew = true; grew;) {
    grew = false;
    for (std::size_t k = 0; k < store.tiles.size(); ++k) {
      for (const std::size_t d : tile_dependencies(store, k)) {
        if (changed.contains(d)) grew = changed.insert(k).second || grew;
      }
    }
  }
  EXPECT_GT(changed.size(), reached.size()) << "later neighbours of reached tiles";
  std::size_t differ = 0;
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    EXPECT_EQ(after.result[k] != before.result[k], changed.contains(k)) << store.tiles[k].key.name();
    EXPECT_EQ(after.inputs[k] != before.inputs[k], reached.contains(k)) << store.tiles[k].key.name();
    differ += after.result[k] != before.result[k] ? 1 : 0;
  }
  EXPECT_GT(differ, 0u);
  EXPECT_LT(differ, store.tiles.size()) << "the eastern tiles are far from acquisition 1";
  // The settings reach every tile; a tile's own counts reach it.
  const TileDigests settings = tile_digests(store, 8, std::vector<std::uint64_t>{100, 200});
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    EXPECT_NE(settings.result[k], before.result[k]);
    EXPECT_NE(settings.inputs[k], before.inputs[k]);
  }
  const std::size_t last = store.tiles.size() - 1;
  ++store.tiles[last].triangles[0][1];
  EXPECT_NE(tile_digests(store, 7, std::vector<std::uint64_t>{100, 200}).inputs[last], before.inputs[last]);
  EXPECT_THROW((void)tile_digests(store, 7, std::vector<std::uint64_t>{100}), ProcessingError);
}

TEST(TilePlan, APassInsertedBeforeOthersLeavesTheInputsOfTheTilesItDoesNotReachButNotTheirResults) {
  std::mt19937 rng(12);
  TileStore store = random_store(rng, 12, 10);  // acquisition 0 everywhere
  for (TileContents& t : store.tiles) t.triangles.push_back({1 + rng() % 50, rng() % 9, 0});  // 1 everywhere
  const TileDigests before = tile_digests(store, 7, std::vector<std::uint64_t>{100, 200});
  // A pass older than acquisition 1 (delivered late) over the western tiles: it becomes 1,
  // and the pass that was 1 becomes 2 everywhere.
  TileStore late = store;
  for (TileContents& t : late.tiles) {
    const std::uint64_t owned = t.key.i < 3 ? 1 + rng() % 50 : 0;
    t.triangles.insert(t.triangles.begin() + 1, {owned, 0, 0});
  }
  const TileDigests after = tile_digests(late, 7, std::vector<std::uint64_t>{100, 150, 200});
  std::size_t same_inputs = 0;
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    const bool reached = late.tiles[k].triangles[1][0] > 0;
    EXPECT_EQ(late.tiles[k].passes(),
              (reached ? std::vector<std::uint32_t>{0, 1, 2} : std::vector<std::uint32_t>{0, 2}));
    // The same passes in the same order: the same inputs, but another numbering of them.
    EXPECT_EQ(after.inputs[k] == before.inputs[k], !reached) << store.tiles[k].key.name();
    EXPECT_NE(after.result[k], before.result[k]) << store.tiles[k].key.name();
    same_inputs += reached ? 0 : 1;
  }
  EXPECT_GT(same_inputs, 0u);
  EXPECT_LT(same_inputs, store.tiles.size());
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
