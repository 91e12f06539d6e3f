// SPDX-License-Identifier: MIT
#include "citymesh/core/packed_pairs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "citymesh/core/parallel.h"

namespace citymesh {
namespace {

using Pairs = std::vector<PackedPairs::Pair>;

/// Pairs like a change step's: runs of one `first` whose seconds spread over `spread`, with
/// jumps between firsts; some lists with duplicates and the extremes of 32 bits.
Pairs change_like_pairs(std::size_t runs, std::uint32_t most_in_run, std::uint32_t spread, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::uint32_t> length(1, most_in_run), jump(0, 40), second(0, spread);
  Pairs out;
  std::uint32_t first = 0;
  for (std::size_t r = 0; r < runs; ++r) {
    first += jump(rng);
    const std::uint32_t base = first + second(rng);
    for (std::uint32_t k = length(rng); k > 0; --k) out.emplace_back(first, base + second(rng));
  }
  return out;
}

Pairs sorted(Pairs p) {
  std::sort(p.begin(), p.end());
  return p;
}

TEST(PackedPairs, GivesBackTheSortedListWhateverTheRunsAndValues) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint32_t> any;
  Pairs extremes;
  for (int k = 0; k < 20'000; ++k) extremes.emplace_back(any(rng) % 3 == 0 ? 0xffffffffu : any(rng), any(rng));
  extremes.emplace_back(0, 0);
  extremes.emplace_back(0xffffffffu, 0xffffffffu);
  extremes.emplace_back(0xffffffffu, 0);
  const std::vector<Pairs> lists{
      {},
      {{5, 3}},
      change_like_pairs(30'000, 40, 5'000, 1),  // several blocks, runs across their borders
      change_like_pairs(10, 9'000, 100, 2),     // runs longer than a block, many duplicates
      extremes,                                 // deltas of any size and sign
  };
  for (const Pairs& list : lists) {
    const Pairs expected = sorted(list);
    const PackedPairs packed(list);  // unsorted lists come sorted back
    EXPECT_EQ(packed.size(), expected.size());
    EXPECT_EQ(packed.empty(), expected.empty());
    EXPECT_EQ(packed.unpacked(), expected);
    EXPECT_EQ(packed.block_count(), (expected.size() + PackedPairs::kBlock - 1) / PackedPairs::kBlock);
  }
}

TEST(PackedPairs, TakesAboutTwoAndAHalfBytesAPairOnChangeLikeLists) {
  const Pairs list = change_like_pairs(20'000, 60, 3'000, 3);
  const PackedPairs packed(list);
  // Runs of ~30 seconds within a few thousand ids: two bytes a delta, a few more a run.
  EXPECT_LT(packed.bytes(), list.size() * 5 / 2);
}

TEST(PackedPairs, ReadsEachBlockOnItsOwn) {
  const Pairs list = sorted(change_like_pairs(8'000, 30, 20'000, 4));
  const PackedPairs packed(list);
  ASSERT_GT(packed.block_count(), 3u);
  for (std::size_t b = 0; b <= packed.block_count(); ++b) {
    const std::size_t from = std::min(b * PackedPairs::kBlock, list.size());
    PackedPairs::Iterator it = packed.block_begin(b);
    ASSERT_EQ(it.index(), from);
    const Pairs tail(it, packed.end());
    EXPECT_EQ(tail, Pairs(list.begin() + static_cast<std::ptrdiff_t>(from), list.end())) << "block " << b;
  }
}

TEST(PackedPairs, LowerBoundFindsTheFirstPairAsTheSortedListDoes) {
  Pairs list = sorted(change_like_pairs(6'000, 50, 1'000, 5));
  // A `first` spanning whole blocks: the bound must go back to the block it starts in.
  const std::uint32_t wide = list[list.size() / 2].first;
  for (int k = 0; k < 3 * static_cast<int>(PackedPairs::kBlock); ++k) list.emplace_back(wide, 7 * k);
  list = sorted(list);
  const PackedPairs packed(list);
  std::mt19937 rng(6);
  std::uniform_int_distribution<std::uint32_t> probe(0, list.back().first + 2);
  std::vector<std::uint32_t> probes{0, wide, wide + 1, list.back().first, list.back().first + 1, 0xffffffffu};
  for (int k = 0; k < 2'000; ++k) probes.push_back(probe(rng));
  for (const std::uint32_t first : probes) {
    const auto expected = std::lower_bound(list.begin(), list.end(), PackedPairs::Pair{first, 0});
    const PackedPairs::Iterator found = packed.lower_bound(first);
    ASSERT_EQ(found.index(), static_cast<std::size_t>(expected - list.begin())) << "first " << first;
    if (found != packed.end()) {
      EXPECT_EQ(*found, *expected);
    }
  }
}

TEST(PackedPairs, SameBytesOnAnyThreadCount) {
  const Pairs list = change_like_pairs(50'000, 40, 8'000, 8);
  const auto pack_on = [&](unsigned threads) {
    const ThreadLimit limit(threads);
    return PackedPairs(list);
  };
  EXPECT_EQ(pack_on(1), pack_on(2));
  EXPECT_EQ(pack_on(1), pack_on(8));
  EXPECT_FALSE(pack_on(1) == PackedPairs(change_like_pairs(50'000, 40, 8'000, 9)));
}

}  // namespace
}  // namespace citymesh
