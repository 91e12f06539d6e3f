// SPDX-License-Identifier: MIT
// The only source that includes TBB.
#include "citymesh/core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>

namespace citymesh {

struct ThreadLimit::Impl {
  explicit Impl(unsigned threads)
      : control(tbb::global_control::max_allowed_parallelism,
                threads == 0 ? tbb::this_task_arena::max_concurrency() : threads) {}
  tbb::global_control control;
};

ThreadLimit::ThreadLimit(unsigned threads) : impl_(std::make_unique<Impl>(threads)) {}
ThreadLimit::~ThreadLimit() = default;

unsigned available_threads() {
  return static_cast<unsigned>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

void parallel_sort(std::span<std::uint64_t> values) { tbb::parallel_sort(values.begin(), values.end()); }

void parallel_for_blocks(std::size_t count, std::size_t grain,
                         const std::function<void(std::size_t, std::size_t)>& body) {
  grain = std::max<std::size_t>(grain, 1);
  const std::size_t blocks = (count + grain - 1) / grain;
  // simple_partitioner with grain 1 over block numbers: block edges are fixed by `grain` alone.
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, blocks, 1),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          body(b * grain, std::min(count, (b + 1) * grain));
        }
      },
      tbb::simple_partitioner());
}

void parallel_workers(unsigned workers, const std::function<void(unsigned)>& body) {
  tbb::parallel_for(
      tbb::blocked_range<unsigned>(0, workers, 1),
      [&](const tbb::blocked_range<unsigned>& r) {
        for (unsigned w = r.begin(); w != r.end(); ++w) {
          tbb::this_task_arena::isolate([&] {
            // An isolated cancellation group: when another worker throws, TBB cancels this
            // loop's context, and without its own group a worker's nested loops would be cut
            // short and return normally - a half-computed tile written as finished.
            tbb::task_group_context own(tbb::task_group_context::isolated);
            tbb::task_group group(own);
            group.run_and_wait([&] { body(w); });
          });
        }
      },
      tbb::simple_partitioner());
}

namespace {

/// The loops of one parallel_loops call: tasks of one group. Each piece of work runs isolated
/// with its own cancellation context; `next` and spawn() run outside, so that a loop's nested
/// waits never pick up a whole loop started meanwhile. Exceptions are kept rather than let
/// out, which would cancel the group and cut the other loops' nested loops short.
class LoopGroup {
 public:
  explicit LoopGroup(const std::function<LoopWork(const LoopSpawner&)>& next) : next_(next) {}

  void spawn(unsigned loops) {
    for (unsigned i = 0; i < loops; ++i) group_.run([this] { run_loop(); });
  }

  /// Waits for every loop, then rethrows the first exception.
  void wait() {
    group_.wait();
    if (first_error_) std::rethrow_exception(first_error_);
  }

 private:
  /// What `next` is handed (task_group's destructor may throw, so the group is no LoopSpawner).
  class Spawner final : public LoopSpawner {
   public:
    explicit Spawner(LoopGroup& group) : group_(group) {}
    void spawn(unsigned loops) const override { group_.spawn(loops); }

   private:
    LoopGroup& group_;
  };

  void run_loop() {
    try {
      for (LoopWork work = next_(spawner_); work; work = next_(spawner_)) {
        tbb::this_task_arena::isolate([&] {
          tbb::task_group_context own(tbb::task_group_context::isolated);
          tbb::task_group nested(own);
          nested.run_and_wait([&] { work(); });
        });
      }
    } catch (...) {
      const std::lock_guard lock(error_mutex_);
      if (!first_error_) first_error_ = std::current_exception();
    }
  }

  const std::function<LoopWork(const LoopSpawner&)>& next_;
  Spawner spawner_{*this};
  tbb::task_group group_;
  std::mutex error_mutex_;
  std::exception_ptr first_error_;
};

}  // namespace

void parallel_loops(unsigned loops, const std::function<LoopWork(const LoopSpawner&)>& next) {
  LoopGroup group(next);
  group.spawn(loops);
  group.wait();
}

void parallel_jobs(std::size_t count, unsigned workers, const std::function<void(std::size_t)>& job) {
  const auto loops = static_cast<unsigned>(std::min<std::size_t>(count, std::max(workers, 1u)));
  if (loops == 0) return;
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  parallel_workers(loops, [&](unsigned) {
    try {
      for (std::size_t i = next++; i < count && !failed; i = next++) job(i);
    } catch (...) {
      failed = true;
      throw;
    }
  });
}

}  // namespace citymesh
