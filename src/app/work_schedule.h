// SPDX-License-Identifier: MIT
// Handing out work: items with costs and dependencies, taken by worker threads of this
// process (LocalChannel) or of every rank of an MPI job (cluster.h), largest ready item first.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <utility>
#include <vector>

namespace citymesh::app {

/// Which items may start: an item is ready once every item it waits for is finished. Ready
/// items are taken largest cost first (ties: lowest index), so big tiles do not end a run alone.
class WorkSchedule {
 public:
  /// `after[k]`: the items k waits for (indices < costs.size(), never k). `done[k]`: finished
  /// already (a resumed run). Throws std::invalid_argument on a bad index.
  WorkSchedule(std::vector<std::uint64_t> costs, const std::vector<std::vector<std::size_t>>& after,
               const std::vector<std::uint8_t>& done);

  /// A ready item, now in flight; nothing when none is ready.
  std::optional<std::size_t> take();
  /// Marks an item taken earlier as finished; items waiting only for it become ready.
  void finish(std::size_t item);

  [[nodiscard]] bool finished() const { return done_ == costs_.size(); }
  [[nodiscard]] std::size_t in_flight() const { return in_flight_; }
  [[nodiscard]] std::size_t ready() const { return ready_.size(); }
  [[nodiscard]] std::size_t size() const { return costs_.size(); }

 private:
  void make_ready(std::size_t item) { ready_.emplace(~costs_[item], item); }

  std::vector<std::uint64_t> costs_;
  std::vector<std::vector<std::size_t>> dependents_;
  std::vector<std::size_t> waiting_;                       ///< unfinished items each item waits for
  std::set<std::pair<std::uint64_t, std::size_t>> ready_;  ///< (~cost, item): largest first
  std::size_t done_ = 0, in_flight_ = 0;
};

/// What a worker gets when it asks for work.
struct WorkReply {
  enum class Kind { item, wait, done } kind = Kind::done;
  std::size_t item = 0;
};

/// Where a worker thread gets its next item.
class WorkChannel {
 public:
  virtual ~WorkChannel() = default;
  /// Reports `finished` (the worker's previous item), then blocks until another item is ready
  /// for this worker; nothing once every item is finished.
  virtual std::optional<std::size_t> next(std::optional<std::size_t> finished) = 0;
  /// Wakes every waiting worker with an error: a worker failed, the others stop.
  virtual void abort() = 0;
};

/// The worker threads of this process sharing one schedule. `on_finish` runs (under the
/// channel's lock) for every finished item, whoever processed it.
class LocalChannel final : public WorkChannel {
 public:
  LocalChannel(WorkSchedule& schedule, std::function<void(std::size_t)> on_finish);
  std::optional<std::size_t> next(std::optional<std::size_t> finished) override;
  void abort() override;
  /// next() without blocking, for a worker elsewhere (another rank): an item, wait or done.
  WorkReply poll(std::optional<std::size_t> finished);

  /// For worker loops that come and go (run_workers, through parallel_loops), which end when
  /// nothing is ready rather than wait: `loops` are running.
  void start_loops(unsigned loops);
  /// A ready item for a running loop, and how many more loops the items still ready can use
  /// within `max_loops` (counted as running from now on: the caller starts them). Without an
  /// item the loop counts as ended. Throws after abort(), and when nothing is ready or in
  /// flight before the end (a cycle). Loops that end and loops that start are counted under
  /// one lock, so an item made ready while a loop ends is never left without one.
  struct LoopTake {
    std::optional<std::size_t> item;
    unsigned more = 0;
  };
  LoopTake take_for_loop(unsigned max_loops);
  /// Marks an item a loop took as finished (on_finish runs under the lock).
  void finish_for_loop(std::size_t item);

 private:
  WorkReply step(std::optional<std::size_t> finished);
  /// Marks `item` finished and tells on_finish; under the lock.
  void finish_locked(std::size_t item);

  WorkSchedule& schedule_;
  std::function<void(std::size_t)> on_finish_;
  std::mutex mutex_;
  std::condition_variable changed_;
  bool aborted_ = false;
  unsigned loops_ = 0;  ///< running loops (take_for_loop)
};

/// Runs up to `workers` loops (on the TBB pool) that take items from `channel` and call `body`
/// on each until every item is finished. On this process's own schedule (LocalChannel) a loop
/// with nothing ready ends and loops start again as items become ready, so that a thread with
/// nothing to do helps the items in flight with their nested parallel loops; on a cluster's
/// channel the loops wait for work. The first exception stops every loop and is rethrown.
void run_workers(WorkChannel& channel, unsigned workers, const std::function<void(std::size_t)>& body);

/// How many items from `first` on to take at once: up to `most`, while the sum of their
/// `bytes` stays within `room`; always at least one (when first < bytes.size()).
std::size_t batch_within(std::span<const std::uint64_t> bytes, std::size_t first, std::size_t most, std::uint64_t room);

}  // namespace citymesh::app
