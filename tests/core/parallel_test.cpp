// SPDX-License-Identifier: MIT
#include "citymesh/core/parallel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

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
/// Blocks of a nested loop, each sleeping a millisecond: long enough that a failing worker
/// throws while they run. Counts the blocks that ran.
constexpr std::size_t kNestedBlocks = 200;
void run_nested_blocks(std::atomic<std::size_t>& blocks_run) {
  parallel_for_blocks(kNestedBlocks, 1, [&](std::size_t, std::size_t) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ++blocks_run;
  });
}

TEST(ParallelWorkers, AThrowingWorkerDoesNotCutShortTheOthersNestedLoops) {
  ThreadLimit limit(2);
  std::atomic<bool> started{false};
  std::atomic<std::size_t> blocks_run{0};
  EXPECT_THROW(parallel_workers(2,
                                [&](unsigned w) {
                                  if (w == 0) {
                                    std::this_thread::sleep_for(std::chrono::milliseconds(30));
                                    throw std::runtime_error("worker 0 fails");
                                  }
                                  started = true;
                                  run_nested_blocks(blocks_run);
                                }),
               std::runtime_error);
  // With one thread worker 1 may never start; once started, its loop must run every block.
  if (started) {
    EXPECT_EQ(blocks_run.load(), kNestedBlocks);
  }
}

/// Work handed out one piece at a time to parallel_loops: a loop that takes the first piece
/// starts as many loops as there are pieces left, up to `most` running; a loop ends when none
/// is left.
struct LoopPieces {
  std::mutex m;
  std::size_t next = 0, count = 0;
  unsigned running = 0, most = 0;
  std::vector<std::atomic<int>> runs;
  LoopPieces(std::size_t n, unsigned loops) : count(n), running(loops), most(loops), runs(n) {}

  LoopWork take(const LoopSpawner& spawner, const std::function<void(std::size_t)>& work) {
    std::size_t piece = 0;
    unsigned more = 0;
    {
      const std::lock_guard lock(m);
      if (next == count) {
        --running;
        return {};
      }
      piece = next++;
      more = static_cast<unsigned>(std::min<std::size_t>(count - next, most - running));
      running += more;
    }
    spawner.spawn(more);
    return [this, piece, &work] {
      work(piece);
      ++runs[piece];
    };
  }
};

TEST(ParallelLoops, LoopsStartedOnTheWayRunEveryPieceOnce) {
  for (const unsigned threads : {1u, 2u, 4u}) {
    ThreadLimit limit(threads);
    LoopPieces pieces(50, 1);  // one loop at first: the others are started by it
    pieces.most = threads;
    std::atomic<int> in_flight{0}, most{0};
    const std::function<void(std::size_t)> work = [&](std::size_t) {
      const int now = ++in_flight;
      for (int seen = most.load(); now > seen && !most.compare_exchange_weak(seen, now);) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      --in_flight;
    };
    parallel_loops(1, [&](const LoopSpawner& spawner) { return pieces.take(spawner, work); });
    for (std::size_t i = 0; i < 50; ++i) EXPECT_EQ(pieces.runs[i].load(), 1) << threads << " threads, piece " << i;
    EXPECT_LE(most.load(), static_cast<int>(threads));
    EXPECT_EQ(pieces.running, 0u);
  }
}

TEST(ParallelLoops, AThrowingLoopDoesNotCutShortTheOthersNestedLoops) {
  ThreadLimit limit(2);
  std::atomic<bool> started{false};
  std::atomic<std::size_t> blocks_run{0};
  LoopPieces pieces(2, 2);
  const std::function<void(std::size_t)> work = [&](std::size_t piece) {
    if (piece == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
      throw std::runtime_error("piece 0 fails");
    }
    started = true;
    run_nested_blocks(blocks_run);
  };
  EXPECT_THROW(parallel_loops(2, [&](const LoopSpawner& spawner) { return pieces.take(spawner, work); }),
               std::runtime_error);
  if (started) {
    EXPECT_EQ(blocks_run.load(), kNestedBlocks);
  }
}

TEST(ParallelLoops, ALoopWithNothingToDoHelpsTheOthersNestedLoops) {
  ThreadLimit limit(2);
  if (available_threads() < 2) GTEST_SKIP() << "one thread";
  // Two loops, one piece: the loop without a piece ends, and its thread takes blocks of the
  // piece's nested loop (a worker loop of parallel_workers waiting for work would not).
  LoopPieces pieces(1, 2);
  std::mutex m;
  std::set<std::thread::id> threads;
  const std::function<void(std::size_t)> work = [&](std::size_t) {
    parallel_for_blocks(64, 1, [&](std::size_t, std::size_t) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      const std::lock_guard lock(m);
      threads.insert(std::this_thread::get_id());
    });
  };
  parallel_loops(2, [&](const LoopSpawner& spawner) { return pieces.take(spawner, work); });
  EXPECT_EQ(pieces.runs[0].load(), 1);
  EXPECT_EQ(threads.size(), 2u);
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
