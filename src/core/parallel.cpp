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
  return static_cast<unsigned>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
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
