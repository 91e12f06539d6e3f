// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <set>
#include <vector>

#include "citymesh/core/parallel.h"

namespace citymesh {
namespace {

std::set<std::pair<std::size_t, std::size_t>> blocks_with(unsigned threads, std::size_t count, std::size_t grain) {
  ThreadLimit limit(threads);
  std::mutex m;
  std::set<std::pair<std::size_t, std::size_t>> blocks;
  parallel_for_blocks(count, grain, [&](std::size_t b, std::size_t e) {
    std::lock_guard lock(m);
    blocks.emplace(b, e);
  });
  return blocks;
}

TEST(ParallelForBlocks, CoversEveryIndexExactlyOnce) {
  std::vector<std::atomic<int>> hits(10'007);
  parallel_for_blocks(hits.size(), 64, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) hits[i].fetch_add(1);
  });
  EXPECT_TRUE(std::all_of(hits.begin(), hits.end(), [](const auto& h) { return h.load() == 1; }));
}

TEST(ParallelForBlocks, BlocksDoNotDependOnTheThreadCount) {
  const auto one = blocks_with(1, 1000, 37);
  EXPECT_EQ(one, blocks_with(2, 1000, 37));
  EXPECT_EQ(one, blocks_with(8, 1000, 37));
  EXPECT_EQ(one.size(), 28u);  // ceil(1000 / 37)
  EXPECT_EQ(one.rbegin()->second, 1000u);
}

TEST(ParallelForBlocks, EmptyRangeCallsNothing) {
  int calls = 0;
  parallel_for_blocks(0, 10, [&](std::size_t, std::size_t) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(ThreadLimit, BoundsTheAvailableThreads) {
  ThreadLimit limit(1);
  EXPECT_EQ(available_threads(), 1u);
}

}  // namespace
}  // namespace citymesh
