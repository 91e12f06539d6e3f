// SPDX-License-Identifier: MIT
// Handing out work: the schedule against a brute-force reference on random dependency graphs,
// worker threads that never start an item before what it waits for, and failures that stop
// every worker instead of hanging.
#include "work_schedule.h"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"

namespace citymesh::app {
namespace {

struct RandomGraph {
  std::vector<std::uint64_t> costs;
  std::vector<std::vector<std::size_t>> after;
  std::vector<std::uint8_t> done;
};

/// Items wait only for items of lower index: acyclic. Some items are done already.
RandomGraph random_graph(std::mt19937& rng, std::size_t n) {
  RandomGraph g;
  std::uniform_int_distribution<std::uint64_t> cost(0, 5);  // ties on purpose
  for (std::size_t k = 0; k < n; ++k) {
    g.costs.push_back(cost(rng));
    std::vector<std::size_t> deps;
    for (std::size_t d = 0; d < k; ++d) {
      if (rng() % 4 == 0) deps.push_back(d);
    }
    g.after.push_back(deps);
    g.done.push_back(rng() % 5 == 0 ? 1 : 0);
  }
  // A done item's dependencies are done too, as in a resumed run.
  for (std::size_t k = n; k-- > 0;) {
    if (g.done[k] != 0) {
      for (const std::size_t d : g.after[k]) g.done[d] = 1;
    }
  }
  return g;
}

TEST(WorkSchedule, HandsOutTheLargestReadyItemLikeBruteForce) {
  std::mt19937 rng(7);
  for (int round = 0; round < 200; ++round) {
    const RandomGraph g = random_graph(rng, 1 + rng() % 14);
    WorkSchedule schedule(g.costs, g.after, g.done);
    std::vector<std::uint8_t> finished = g.done, taken = g.done;
    std::vector<std::size_t> in_flight;
    while (!schedule.finished()) {
      // Brute force: the ready items, largest cost first, then lowest index.
      std::optional<std::size_t> expected;
      for (std::size_t k = 0; k < g.costs.size(); ++k) {
        if (taken[k] != 0) continue;
        bool ready = true;
        for (const std::size_t d : g.after[k]) ready = ready && finished[d] != 0;
        if (ready && (!expected || g.costs[k] > g.costs[*expected])) expected = k;
      }
      // Take while something is ready, finishing a random in-flight item now and then.
      if (expected && (in_flight.empty() || rng() % 2 == 0)) {
        const std::optional<std::size_t> got = schedule.take();
        ASSERT_EQ(got, expected) << "round " << round;
        taken[*got] = 1;
        in_flight.push_back(*got);
      } else {
        ASSERT_FALSE(in_flight.empty()) << "nothing ready, nothing in flight, not finished";
        if (!expected) {
          EXPECT_EQ(schedule.take(), std::nullopt);
        }
        const std::size_t at = rng() % in_flight.size();
        schedule.finish(in_flight[at]);
        finished[in_flight[at]] = 1;
        in_flight.erase(in_flight.begin() + static_cast<std::ptrdiff_t>(at));
      }
    }
    // Every item finished; items done before the schedule started were never handed out
    // (the reference skips them and every take matched it).
    for (std::size_t k = 0; k < g.costs.size(); ++k) EXPECT_NE(finished[k], 0);
  }
}

TEST(BatchWithin, TakesTheLongestRunFromFirstThatFitsTheRoomAndAlwaysOne) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<std::uint64_t> bytes(rng() % 8);
    for (std::uint64_t& b : bytes) b = rng() % 100;
    const std::size_t first = rng() % (bytes.size() + 1), most = rng() % 5;
    const std::uint64_t room = rng() % 250;
    // Brute force: the largest count <= most whose run from first sums within the room,
    // at least one item when there is one to take.
    std::size_t expected = 0;
    for (std::size_t count = 1; count <= most && first + count <= bytes.size(); ++count) {
      std::uint64_t sum = 0;
      for (std::size_t k = first; k < first + count; ++k) sum += bytes[k];
      if (count == 1 || sum <= room) expected = count;
      if (sum > room) break;
    }
    ASSERT_EQ(batch_within(bytes, first, most, room), expected) << trial;
  }
}

TEST(WorkSchedule, RefusesBadDependencies) {
  EXPECT_THROW(WorkSchedule({1, 1}, {{1}, {5}}, {0, 0}), std::invalid_argument);
  EXPECT_THROW(WorkSchedule({1}, {{0}}, {0}), std::invalid_argument);
  EXPECT_THROW(WorkSchedule({1, 1}, {{}}, {0, 0}), std::invalid_argument);
}

TEST(LocalChannel, WorkersRunEveryItemOnceAfterWhatItWaitsFor) {
  std::mt19937 rng(11);
  for (unsigned threads : {1u, 2u, 4u}) {
    const ThreadLimit limit(threads);
    const RandomGraph g = random_graph(rng, 60);
    WorkSchedule schedule(g.costs, g.after, g.done);
    std::vector<std::atomic<int>> runs(g.costs.size());
    std::vector<std::atomic<std::uint8_t>> finished(g.costs.size());
    for (std::size_t k = 0; k < g.costs.size(); ++k) finished[k] = g.done[k];
    std::atomic<bool> early = false;
    std::size_t reported = 0;
    LocalChannel channel(schedule, [&](std::size_t) { ++reported; });
    std::atomic<unsigned> in_flight{0}, most{0};
    run_workers(channel, threads, [&](std::size_t k) {
      const unsigned now = ++in_flight;
      for (unsigned seen = most.load(); now > seen && !most.compare_exchange_weak(seen, now);) {
      }
      for (const std::size_t d : g.after[k]) early = early || finished[d] == 0;
      std::this_thread::sleep_for(std::chrono::microseconds(200 * g.costs[k]));
      ++runs[k];
      finished[k] = 1;
      --in_flight;
    });
    EXPECT_FALSE(early) << threads << " threads: an item started before its dependencies";
    EXPECT_LE(most.load(), threads) << "more items in flight than workers";
    std::size_t expected = 0;
    for (std::size_t k = 0; k < g.costs.size(); ++k) {
      EXPECT_EQ(runs[k].load(), g.done[k] != 0 ? 0 : 1) << "item " << k;
      expected += g.done[k] != 0 ? 0 : 1;
    }
    EXPECT_EQ(reported, expected);
  }
}

TEST(LocalChannel, AWorkerWithNothingReadyHelpsTheItemInFlight) {
  const ThreadLimit limit(2);
  if (available_threads() < 2) GTEST_SKIP() << "one thread";
  // Item 1 waits for item 0: while item 0 runs, the other worker has nothing to take, and its
  // thread must help item 0's nested loop rather than sleep (four tiles in four phases).
  WorkSchedule schedule({2, 1}, {{}, {0}}, {0, 0});
  LocalChannel channel(schedule, nullptr);
  std::mutex m;
  std::set<std::thread::id> threads;
  run_workers(channel, 2, [&](std::size_t k) {
    if (k != 0) return;
    parallel_for_blocks(64, 1, [&](std::size_t, std::size_t) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      const std::lock_guard lock(m);
      threads.insert(std::this_thread::get_id());
    });
  });
  EXPECT_TRUE(schedule.finished());
  EXPECT_EQ(threads.size(), 2u);
}

TEST(LocalChannel, AFailingWorkerStopsTheOthersInsteadOfHanging) {
  const ThreadLimit limit(2);
  // Item 1 waits for item 0, which fails: the worker waiting for it must not wait forever.
  WorkSchedule schedule({5, 1, 1}, {{}, {0}, {}}, {0, 0, 0});
  LocalChannel channel(schedule, nullptr);
  EXPECT_THROW(run_workers(channel, 2,
                           [&](std::size_t k) {
                             if (k == 0) {
                               std::this_thread::sleep_for(std::chrono::milliseconds(50));
                               throw InputError("broken tile");
                             }
                           }),
               Error);
}

TEST(LocalChannel, ACycleIsAnErrorNotAHang) {
  // Items 0 and 1 wait for each other: nothing is ever ready.
  WorkSchedule schedule({1, 1}, {{1}, {0}}, {0, 0});
  LocalChannel channel(schedule, nullptr);
  EXPECT_THROW(run_workers(channel, 2, [](std::size_t) {}), ProcessingError);
}

}  // namespace
}  // namespace citymesh::app
