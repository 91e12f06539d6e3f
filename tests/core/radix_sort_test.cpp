// SPDX-License-Identifier: MIT
#include "citymesh/core/radix_sort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace citymesh {
namespace {

using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

Pairs random_pairs(std::size_t n, std::uint32_t first_max, std::uint32_t second_max, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::uint32_t> first(0, first_max), second(0, second_max);
  Pairs out(n);
  for (auto& p : out) p = {first(rng), second(rng)};
  return out;
}

void expect_sorted_like_std(Pairs values) {
  Pairs expected = values;
  std::sort(expected.begin(), expected.end());
  radix_sort_pairs(values);
  EXPECT_EQ(values, expected);
}

TEST(RadixSortPairs, MatchesStdSortOnSmallAndLargeKeys) {
  expect_sorted_like_std(random_pairs(10'000, 300'000, 300'000, 1));          // triangle ids
  expect_sorted_like_std(random_pairs(10'000, 0xffffffffu, 0xffffffffu, 2));  // every digit used
  expect_sorted_like_std(random_pairs(5'000, 7, 3, 3));                       // many ties
  expect_sorted_like_std(random_pairs(3'000, 0, 0xffffffffu, 4));             // first all zero
  expect_sorted_like_std(random_pairs(3'001, (1u << 30) - 1, 0, 5));          // odd pass count
}

TEST(RadixSortPairs, LargeListsSplitInPlaceFirstAndStillMatchStdSort) {
  constexpr std::size_t kLarge = (std::size_t{1} << 20) + 3;                  // past the in-place split
  expect_sorted_like_std(random_pairs(kLarge, 3'000'000, 3'000'000, 6));      // a spinning tile's ids
  expect_sorted_like_std(random_pairs(kLarge, 0xffffffffu, 0xffffffffu, 7));  // the top bit in use
  expect_sorted_like_std(random_pairs(kLarge, 0, 100, 8));                    // every key below 8 bits
  expect_sorted_like_std(random_pairs(kLarge, 1, 0xffffffffu, 9));            // two parts only
  Pairs skewed = random_pairs(kLarge, 1'000, 50'000, 10);                     // one part holds nearly all
  for (std::size_t k = 0; k < 100; ++k) skewed[k].first = 0xfffffff0u;
  expect_sorted_like_std(skewed);
}

TEST(RadixSortPairs, EdgeCases) {
  expect_sorted_like_std({});
  expect_sorted_like_std({{5, 1}});
  expect_sorted_like_std({{0, 0}, {0, 0}});
  expect_sorted_like_std({{2, 1}, {1, 2}, {1, 1}, {0xffffffffu, 0}, {0, 0xffffffffu}});
}

void expect_stable_by_first_like_std(Pairs values) {
  Pairs expected = values;
  std::stable_sort(expected.begin(), expected.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  stable_radix_sort_by_first(values);
  EXPECT_EQ(values, expected);
}

TEST(RadixSortPairs, ByFirstKeepsTheOrderOfTiesAsStdStableSortDoes) {
  // Seconds in no order: the ties must keep it, not sort it.
  expect_stable_by_first_like_std(random_pairs(10'000, 0xffffffffu, 0xffffffffu, 6));
  expect_stable_by_first_like_std(random_pairs(5'000, 7, 1000, 7));         // many ties
  expect_stable_by_first_like_std(random_pairs(3'000, 0, 0xffffffffu, 8));  // first all zero
  expect_stable_by_first_like_std({});
  expect_stable_by_first_like_std({{3, 9}, {1, 8}, {3, 2}, {1, 1}, {0xffffffffu, 0}, {3, 5}});
  // Pairs made in index order come out as radix_sort_pairs() sorts them.
  Pairs indexed = random_pairs(4'000, 50, 0, 9);
  for (std::uint32_t i = 0; i < indexed.size(); ++i) indexed[i].second = i;
  Pairs full = indexed;
  radix_sort_pairs(full);
  stable_radix_sort_by_first(indexed);
  EXPECT_EQ(indexed, full);
}

}  // namespace
}  // namespace citymesh
