// SPDX-License-Identifier: MIT
// Thread pool control and deterministic parallel loops (TBB behind this header).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace citymesh {

/// Limits the worker threads of every parallel loop while alive. 0 means all cores.
class ThreadLimit {
 public:
  explicit ThreadLimit(unsigned threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Threads a parallel loop may use now.
[[nodiscard]] unsigned available_threads();

/// Calls `body(begin, end)` on disjoint blocks covering [0, count). Block boundaries depend only
/// on `count` and `grain` (never on the thread count), so a body that writes per-block results
/// that are then combined in block order gives the same bytes on 1 or N threads.
void parallel_for_blocks(std::size_t count, std::size_t grain,
                         const std::function<void(std::size_t, std::size_t)>& body);

/// `item(i)` for every i < count, one item at a time on the pool's threads, in a vector
/// indexed by i.
template <class Result>
std::vector<Result> parallel_map(std::size_t count, const std::function<Result(std::size_t)>& item) {
  std::vector<Result> out(count);
  parallel_for_blocks(count, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out[i] = item(i);
  });
  return out;
}

/// Sorts `values` ascending on the pool. Plain integers: the result is the same on 1 or N
/// threads.
void parallel_sort(std::span<std::uint64_t> values);

/// Runs `body(w)` for every w in [0, workers) on the pool, as long-lived worker loops. Each
/// body runs isolated: while it waits for its own nested parallel loops, its thread runs only
/// their tasks, never another worker loop, so a body may block until another body's work is
/// done without deadlock. A body that throws ends the call with its exception, but never cuts
/// short the nested loops of the bodies still running: they finish whatever they started.
void parallel_workers(unsigned workers, const std::function<void(unsigned)>& body);

/// Starts more loops of the parallel_loops call it was handed by.
class LoopSpawner {
 public:
  virtual ~LoopSpawner() = default;
  /// Starts `loops` more loops; they run once a thread of the pool is free.
  virtual void spawn(unsigned loops) const = 0;
};

/// A loop's next piece of work; empty when the loop ends.
using LoopWork = std::function<void()>;

/// Runs `loops` worker loops on the pool, each calling `next(spawner)` for its next piece of
/// work and running it isolated (as parallel_workers runs its bodies), until `next` gives
/// none. Unlike parallel_workers' loops, these never wait for work: a loop with nothing to do
/// ends, and its thread helps the loops still working with their nested parallel loops (a
/// waiting worker loop holds its thread: four tiles in four phases ran on one core). `next`
/// runs outside the isolation and may start more loops with `spawner` when work becomes
/// ready; the caller keeps count of them. Returns once every loop has ended; a loop that
/// throws (in `next` or in its work) ends the call with its exception (the first thrown) once
/// the others are done, never cutting their nested loops short.
void parallel_loops(unsigned loops, const std::function<LoopWork(const LoopSpawner&)>& next);

/// Runs `job(i)` for every i in [0, count) on min(workers, count) isolated worker loops (as
/// parallel_workers), each taking the next index as soon as it is done with one: at most
/// `workers` jobs are in flight, whatever their lengths. The first job that throws ends the
/// call with its exception once the jobs in flight are done; no worker takes another job.
void parallel_jobs(std::size_t count, unsigned workers, const std::function<void(std::size_t)>& job);

}  // namespace citymesh
