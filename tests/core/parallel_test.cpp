// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <mutex>
#include <random>
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

// A worker that throws must not cut short another worker's nested loop: the loop would return
// normally with blocks skipped, and a tile computed by it would be written as finished.
TEST(ParallelWorkers, AThrowingWorkerDoesNotCutShortTheOthersNestedLoops) {
  ThreadLimit limit(2);
  constexpr std::size_t kBlocks = 200;
  std::atomic<bool> started{false};
  std::atomic<std::size_t> blocks_run{0};
  EXPECT_THROW(parallel_workers(2,
                                [&](unsigned w) {
                                  if (w == 0) {
                                    std::this_thread::sleep_for(std::chrono::milliseconds(30));
                                    throw std::runtime_error("worker 0 fails");
                                  }
                                  started = true;
                                  parallel_for_blocks(kBlocks, 1, [&](std::size_t, std::size_t) {
                                    std::this_thread::sleep_for(std::chrono::milliseconds(1));
                                    ++blocks_run;
                                  });
                                }),
               std::runtime_error);
  // With one thread worker 1 may never start; once started, its loop must run every block.
  if (started) {
    EXPECT_EQ(blocks_run.load(), kBlocks);
  }
}

TEST(ParallelJobs, RunsEveryJobOnceWithAtMostWorkersInFlight) {
  ThreadLimit limit(2);
  constexpr std::size_t kJobs = 40;
  std::vector<std::atomic<int>> runs(kJobs);
  std::atomic<int> in_flight{0}, most{0};
  parallel_jobs(kJobs, 2, [&](std::size_t i) {
    const int now = ++in_flight;
    for (int seen = most.load(); now > seen && !most.compare_exchange_weak(seen, now);) {
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ++runs[i];
    --in_flight;
  });
  for (std::size_t i = 0; i < kJobs; ++i) EXPECT_EQ(runs[i].load(), 1) << i;
  EXPECT_LE(most.load(), 2);
  EXPECT_GE(most.load(), 1);
}

TEST(ParallelJobs, NoJobIsTakenAfterOneThrows) {
  ThreadLimit limit(2);
  std::atomic<std::size_t> started{0};
  EXPECT_THROW(parallel_jobs(1000, 2,
                             [&](std::size_t i) {
                               ++started;
                               std::this_thread::sleep_for(std::chrono::milliseconds(1));
                               if (i == 3) throw std::runtime_error("job 3 fails");
                             }),
               std::runtime_error);
  // Jobs 0 to 3 and the few the other worker started before it saw the failure (a loaded
  // machine may delay the throwing thread), never the thousand.
  EXPECT_LE(started.load(), 20u);
}

TEST(ParallelJobs, NoJobsAndNoWorkersAreFine) {
  int calls = 0;
  parallel_jobs(0, 4, [&](std::size_t) { ++calls; });
  EXPECT_EQ(calls, 0);
  parallel_jobs(3, 0, [&](std::size_t) { ++calls; });  // 0 workers: one loop
  EXPECT_EQ(calls, 3);
}

TEST(ThreadLimit, BoundsTheAvailableThreads) {
  ThreadLimit limit(1);
  EXPECT_EQ(available_threads(), 1u);
}

}  // namespace
}  // namespace citymesh

namespace citymesh {
namespace {

TEST(ParallelSort, EqualsStdSortWithDuplicatesOnOneAndTwoThreads) {
  std::mt19937_64 rng(11);
  std::vector<std::uint64_t> values(300000);
  for (std::uint64_t& v : values) v = rng() % 50000;  // many duplicates
  std::vector<std::uint64_t> expected = values;
  std::sort(expected.begin(), expected.end());
  for (const unsigned threads : {1u, 2u}) {
    const ThreadLimit limit(threads);
    std::vector<std::uint64_t> sorted = values;
    parallel_sort(sorted);
    EXPECT_EQ(sorted, expected) << threads << " threads";
  }
}

}  // namespace
}  // namespace citymesh
